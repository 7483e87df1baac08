// The flat rigid punch on the MFS local model: the analytic reference of the haptic node-count knob.
#pragma once

#include "host/haptics/mfs_local.h"

namespace inc {

// Force (N) of a flat rigid frictionless cylindrical punch of radius a pressed delta into an elastic
// half-space (Sneddon 1965; Boussinesq): F = 2 a E delta / (1 - nu^2).
double flatPunchForce(double radius_m, double youngs_modulus_pa, double poisson_ratio, double indentation_m);

// The punch problem on a hemisphereCloud: the punch face is the surface nodes of the first `contact_shells`
// shells (inner spacing a / (contact_shells + 0.5), so the punch edge lies midway between the last contact
// ring and the next), with only u_z prescribed (frictionless) and the eq. 5 singular weight; the outer shell
// of a half-ball of radius domain_over_radius * a is held. More contact shells = more nodes everywhere (the
// shells beyond grow by `growth`): the node-count knob of the haptic local model.
struct MfsPunchSpec {
  double radius_m = 5e-3;            // a
  int contact_shells = 2;            // >= 1
  double domain_over_radius = 12.0;  // half-ball radius / a, >= 2
  double growth = 1.5;
  double indentation_m = 0.0;  // 0: 1e-3 a (linear elasticity: the ratio does not depend on it)
  int ticks = 2000;            // haptic ticks timed (>= 16)
};

struct MfsPunchResult {
  int nodes = 0;
  int contact_nodes = 0;
  double force_n = 0.0;      // the reaction the tool feels, N
  double analytic_n = 0.0;   // flatPunchForce
  double setup_s = 0.0;      // assembly + condensation (eq. 6), paid once per contact configuration
  double tick_ms = 0.0;      // median wall time of one haptic tick (reactionForce), ms
  double tick_cpu_ms = 0.0;  // the same in CPU time of the process, ms
};

// Builds the cloud and the model, condenses, times `ticks` haptic ticks. Throws InputError for a bad spec.
MfsPunchResult mfsFlatPunch(const MfsPunchSpec& spec, const Material& material);

}  // namespace inc
