// The tool tip against a tissue plane: the MFS local model's tip stiffness and a probe (contact without cutting).
#pragma once

#include "host/haptics/cutting_tool.h"
#include "host/haptics/haptic_loop.h"
#include "host/haptics/mfs_local.h"

namespace inc {

// The local model condensed to the tool tip (eq. 6 with the outer shell held, U_c = 0): f_a = S_aa U_a, a 3 x 3
// stiffness, turned from the half-ball's frame (z = outward normal) into the world. A haptic tick is one 3 x 3
// product (no allocation); the factorisation happens once, here.
struct TipStiffness {
  double k_n_per_m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};  // world frame
  // Force on the hand (N) for the tip displaced by d_m from its anchor: the tissue pushes back, -K d.
  Vec3d handForce(const Vec3d& d_m) const {
    Vec3d f;
    for (int i = 0; i < 3; ++i) f[i] = -(k_n_per_m[i][0] * d_m.x + k_n_per_m[i][1] * d_m.y + k_n_per_m[i][2] * d_m.z);
    return f;
  }
};
// A hemisphereCloud of radius_m with inner shells spacing_m apart (2 inner shells, then growing), the tip node with
// the singular weight of eq. 5, the outer shell held. Throws InputError for a bad size.
TipStiffness mfsTipStiffness(const Material& material, double radius_m, double spacing_m, const Vec3d& unit_normal);
// The elastic model of a tool whose tissue is this tip stiffness alone (no global model): -K d in contact.
CuttingTool::Elastic tipElastic(const TipStiffness& tip);

// A probe on a tissue plane (point, outward unit normal), for models that cannot be cut: below the plane the
// tissue point where the tip entered is the anchor and the hand feels the elastic reaction of the tip's
// displacement from it; above the plane, no force (a linear model would pull the tip back in).
class ProbeTool {
 public:
  ProbeTool(CuttingTool::Elastic elastic, const Vec3d& surface_point_m, const Vec3d& unit_normal);
  ForceResult tick(const ForceRequest& request);
  bool inContact() const { return in_contact_; }

 private:
  CuttingTool::Elastic elastic_;
  Vec3d surface_, normal_, anchor_;
  bool in_contact_ = false;
};

}  // namespace inc
