// Test fixture: the dissection tests' block, a 6 x 4 x 3 cm box of 1 cm metaballs cut by a vertical scalpel.
#pragma once

#include <utility>
#include <vector>

#include "host/scene/scene.h"
#include "host/sim/simulation_model.h"

namespace inc::cuttest {

// The bare block every cutting test starts from: a 6 x 4 x 3 cm box of 1 cm lattice metaballs with cutting on,
// 2 PBD substeps of 5 iterations, the default material and cutting options, nothing fixed, no tool. Without
// gravity unless asked (then the scene default, -9.81 m/s^2 along z). `file` names it in error messages.
inline Scene dissectionBlock(const char* file, bool gravity = false) {
  Scene s;
  s.file = file;
  s.geometry.kind = GeometrySpec::Kind::Box;
  s.geometry.size = Vec3d(0.06, 0.04, 0.03);
  s.geometry.spacing = 0.01;
  s.models.pbd_metaballs = true;
  s.models.cutting = true;
  if (!gravity) s.solver.gravity = Vec3d(0, 0, 0);
  s.solver.substeps = 2;
  s.pbd.iterations = 5;
  return s;
}

// A scalpel with a vertical 8 cm blade (edge along +z) following `path`.
inline ToolSpec scalpel(std::vector<ToolKeyframe> path) {
  ToolSpec t;
  t.name = "scalpel";
  t.kind = "scalpel";
  t.length = 0.08;
  t.path = std::move(path);
  return t;
}

// The straight stroke through the block in the plane y = 2 mm: from x = -5 cm at `enter_s` to +5 cm at `leave_s`.
inline ToolSpec straightScalpel(double enter_s, double leave_s) {
  return scalpel(
      {{enter_s, Vec3d(-0.05, 0.002, 0.0), Vec3d(0, 0, 1)}, {leave_s, Vec3d(0.05, 0.002, 0.0), Vec3d(0, 0, 1)}});
}

// The scripted scalpel moved past any test's frames (100 s on): the block is cut by a mouse or device stroke.
inline ToolSpec parkedScalpel() { return straightScalpel(100.0, 101.0); }

// No gravity, nothing fixed, E = 20 kPa with damping 20 / s, 2 PBD substeps of 5 iterations, 3 lattice cells per
// converted sphere, 2 exchanges per frame. A vertical 8 cm blade sweeps the plane y = 2 mm from x = -5 cm at 0.05 s
// to x = +5 cm at `leave_s` (it leaves the tissue then).
inline Scene cutBlockScene(double leave_s) {
  Scene s = dissectionBlock("<test:cut_block>");
  s.material.youngs_modulus_pa = 2.0e4;
  s.material.damping_per_s = 20.0;
  s.cutting.samples_per_diameter = 3;
  s.cutting.exchanges_per_frame = 2;
  s.tools = {straightScalpel(0.05, leave_s)};
  return s;
}

// The same block named `file` (for error messages), falling under gravity or, without it, at rest.
inline Scene cutBlockScene(double leave_s, bool gravity, const char* file) {
  Scene s = cutBlockScene(leave_s);
  s.file = file;
  if (gravity) s.solver.gravity = Vec3d(0, 0, -9.81);
  return s;
}

// The block for a mouse scalpel: the scripted one moved past any test's frames (100 s on).
inline Scene mouseCutBlockScene(bool gravity, const char* file) {
  Scene s = cutBlockScene(0.15, gravity, file);
  s.tools = {parkedScalpel()};
  return s;
}

// A mouse scalpel event (the phase and tip are the caller's): a vertical 8 cm blade, as the scripted one.
inline ToolEvent mouseScalpel() {
  ToolEvent e;
  e.kind = ToolKind::Cut;
  e.axis = Vec3d(0, 0, -1);
  e.blade_length_m = 0.08;
  return e;
}

}  // namespace inc::cuttest
