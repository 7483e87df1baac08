// Fixtures of the haptic replay tests: a metaball block cut by a scripted scalpel through the cutting force model.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "host/haptics/haptic_cut_session.h"
#include "host/haptics/mfs_local.h"
#include "host/scene/scene_compile.h"
#include "host/sim/dissection_simulation.h"
#include "tests/support/cut_block_scene.h"

namespace inc::hapticreplay {

// A 6 x 4 x 3 cm block of 1 cm metaballs without gravity, cut only by the haptic device (no scripted
// scalpel); the cutting thresholds come from the scene's material.
inline Scene blockScene() {
  Scene s = cuttest::dissectionBlock("<test:haptic_block>");
  s.models.haptics = true;
  s.material.youngs_modulus_pa = 3e3;
  s.cut_thresholds.press_n = 0.02;     // F_p
  s.cut_thresholds.static_n = 0.008;   // F_s
  s.cut_thresholds.dynamic_n = 0.004;  // F_d
  s.cut_thresholds.friction_per_depth_n_per_m = 5.0;
  return s;
}

// The local MFS model alone (tool tip prescribed, outer shell held): force on the hand for a tip
// displacement, frame = world (the block's top face has the outward normal +z).
struct TipModel {
  std::unique_ptr<MfsLocalModel> m;
  Eigen::VectorXd zero;
  TipModel() {
    HemisphereCloudSpec spec;
    spec.inner_spacing_m = 2e-3;
    spec.inner_shells = 2;
    spec.radius_m = 8e-3;
    HemisphereCloud cc = hemisphereCloud(spec);
    cc.cloud.singular[0] = 1;
    const int N = int(cc.cloud.nodes.size());
    std::vector<DofRole> roles(3 * N, DofRole::kFree);
    for (int k = 0; k < 3; ++k) roles[k] = DofRole::kPrescribed;
    for (int i = 1; i < N; ++i)
      if (cc.node_shell[i] == int(cc.shell_r_m.size()) - 1)
        for (int k = 0; k < 3; ++k) roles[3 * i + k] = DofRole::kCoupled;
    m = std::make_unique<MfsLocalModel>(cc.cloud, Material{3e3, 0.45});
    m->setRoles(roles, false);
    zero = Eigen::VectorXd::Zero(Eigen::Index(m->coupledDofs().size()));
  }
  ForceResult operator()(const Vec3d& d) const {
    const Eigen::VectorXd f = m->reactionForce(Eigen::Vector3d(d.x, d.y, d.z), zero);
    ForceResult r;
    r.force_n = Vec3d{-f[0], -f[1], -f[2]};
    return r;
  }
};

// The scalpel: above the block 0.5 mm inside its -x end, pressed 4 mm in, drawn along +x past the far end
// (the cut starts once the elastic drag passes F_s, about 1 mm on, so the stroke spans the whole section),
// halted (the friction vanishes: stop -> the cut is applied), lifted.
inline Trajectory authoredStroke() {
  Trajectory tr;
  auto add = [&](double t, double x, double z) {
    DeviceSample s;
    s.t_s = t;
    s.position_m = {x, 0.002, z};
    tr.samples.push_back(s);
  };
  const double top = 0.015;
  add(0.0, -0.0295, top + 0.003);
  add(0.1, -0.0295, top - 0.004);
  add(0.5, 0.045, top - 0.004);
  add(0.6, 0.045, top - 0.004);
  add(0.7, 0.045, top + 0.003);
  return tr;
}

struct SessionRun {
  std::vector<TickRecord> ticks;
  std::vector<SessionFrame> frames;
  Trajectory recorded;
  std::vector<std::string> messages;
};

inline SessionRun runSession(HapticDevice& device, int frames, BackendKind backend = BackendKind::Cpu,
                             Precision precision = Precision::Float64) {
  const Scene scene = blockScene();
  auto sim = makeDissectionSimulation(compileScene(scene), backend, precision);
  const TipModel tip;
  CuttingTool tool([&tip](const TipContact& c) { return tip(c.displacement_m); }, scene.cut_thresholds,
                   Vec3d{0, 0, 0.015}, Vec3d{0, 0, 1});
  HapticCutSessionConfig cfg;
  cfg.frame_dt_s = 0.02;
  cfg.blade_length_m = 0.08;  // vertical blade through the whole block height
  HapticCutSession session(*sim, device, tool, cfg);
  session.runFrames(frames);
  SessionRun r;
  r.ticks = session.loop().records();
  r.frames = session.frames();
  r.recorded = session.loop().recordedTrajectory();
  r.messages = session.messages();
  return r;
}

}  // namespace inc::hapticreplay
