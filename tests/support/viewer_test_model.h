// A small test double SimulationModel for the viewer tests: a ball that sags under a load, relaxing in time.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "host/sim/simulation_model.h"
#include "tests/support/viewer_test_support.h"

namespace inc::viewer::testing {

// Surface nodes of an icosphere; at equilibrium each node sinks by u_y = -(q / E) (x - x_min)^2 (a clamped
// left side, a load q in N/m^3-like units), so the largest deflection is q L^2 / E with L the diameter.
// advance(dt) relaxes towards it with time constant tau: u <- u_eq + (u - u_eq) exp(-dt / tau).
class SaggingBall : public SimulationModel {
 public:
  explicit SaggingBall(double radius_m = 0.1, double youngs_pa = 1e4, double load = 50.0, int levels = 3)
      : surface_(icosphere(levels, radius_m, {0, 0, 0})), rest_(surface_.vertices), youngs_(youngs_pa), load_(load) {
    x_min_ = -radius_m;
    current_ = rest_;
  }
  std::string name() const override { return "sagging-ball (test double)"; }
  BackendKind backend() const override { return BackendKind::Cpu; }
  std::size_t particleCount() const override { return rest_.size(); }
  void setYoungsModulus(double e) { youngs_ = e; }
  double youngsModulus() const { return youngs_; }
  void poisonNextFrame() { poison_ = true; }

  FrameReport advance(double frame_dt) override {
    FrameReport r;
    r.substeps = 1;
    r.dt = frame_dt * step_scale_;
    const double decay = std::exp(-frame_dt / tau_);
    double ke = 0.0, ee = 0.0, umax = 0.0;
    for (std::size_t i = 0; i < rest_.size(); ++i) {
      const double dx = rest_[i].x - x_min_;
      const double u_eq = -(load_ / youngs_) * dx * dx;
      const double u_old = current_[i].y - rest_[i].y;
      const double u = u_eq + (u_old - u_eq) * decay;
      current_[i].y = rest_[i].y + u;
      const double v = (u - u_old) / frame_dt;
      ke += 0.5 * 1e-3 * v * v;
      ee += 0.5 * youngs_ * 1e-6 * u * u;
      umax = std::max(umax, std::fabs(u));
    }
    if (poison_) {
      current_[7].y = std::numeric_limits<double>::quiet_NaN();
      r.finite = false;
      r.failure_stage = "integrate";
      r.failure_particle = 7;
      poison_ = false;
    }
    r.kinetic_energy = ke;
    r.elastic_energy = ee;
    r.max_displacement = umax;
    r.stages = {{"relax", 0.01}, {"energy", 0.002}};
    r.counters["youngs_pa"] = youngs_;
    ++frames_;
    return r;
  }
  void saveCheckpoint() override { saved_ = current_; }
  void restoreCheckpoint() override { current_ = saved_; }
  void scaleTimeStep(double factor) override { step_scale_ *= factor; }
  double stepScale() const { return step_scale_; }
  void currentPositions(std::vector<Vec3d>& out) const override { out = current_; }
  bool currentSurface(TriangleMesh& out) const override {
    out.triangles = surface_.triangles;
    out.vertices = current_;
    return true;
  }
  MemoryReport memory() const override { return {0, current_.size() * sizeof(Vec3d) * 3}; }
  int frames() const { return frames_; }

 private:
  TriangleMesh surface_;
  std::vector<Vec3d> rest_, current_, saved_;
  double youngs_, load_, x_min_ = 0.0, tau_ = 0.02, step_scale_ = 1.0;
  bool poison_ = false;
  int frames_ = 0;
};

// The same ball opened by a cut: triangles whose centroid lies above y = cut_y are removed, so the inside
// (the cut wall, drawn in the back-face colour) shows through the opening.
class CutBall : public SaggingBall {
 public:
  explicit CutBall(double cut_y) : cut_y_(cut_y) {}
  std::string name() const override { return "cut ball (test double)"; }
  bool currentSurface(TriangleMesh& out) const override {
    TriangleMesh full;
    SaggingBall::currentSurface(full);
    out.vertices = full.vertices;
    out.triangles.clear();
    for (const auto& t : full.triangles)
      if ((full.vertices[t[0]].y + full.vertices[t[1]].y + full.vertices[t[2]].y) / 3.0 < cut_y_)
        out.triangles.push_back(t);
    return true;
  }

 private:
  double cut_y_;
};

// A fixed surface (e.g. a real organ) opened by a planar cut: triangles with a vertex within half_width_m of
// the plane dot(x - point, normal) = 0 are removed, leaving a slot whose walls show the inside.
class CutMeshModel : public SimulationModel {
 public:
  CutMeshModel(TriangleMesh mesh, const Vec3d& point, const Vec3d& normal, double half_width_m)
      : mesh_(std::move(mesh)) {
    std::vector<std::array<int, 3>> kept;
    for (const auto& t : mesh_.triangles) {
      bool near_plane = false;
      for (int k = 0; k < 3; ++k) near_plane |= std::fabs(dot(mesh_.vertices[t[k]] - point, normal)) < half_width_m;
      if (!near_plane) kept.push_back(t);
    }
    removed_ = mesh_.triangles.size() - kept.size();
    mesh_.triangles.swap(kept);
  }
  std::string name() const override { return "organ surface with a planar cut (test double)"; }
  BackendKind backend() const override { return BackendKind::Cpu; }
  std::size_t particleCount() const override { return mesh_.vertices.size(); }
  FrameReport advance(double frame_dt) override {
    FrameReport r;
    r.substeps = 1;
    r.dt = frame_dt;
    r.stages = {{"static", 0.0}};
    r.counters["removed_triangles"] = double(removed_);
    return r;
  }
  void saveCheckpoint() override {}
  void restoreCheckpoint() override {}
  void scaleTimeStep(double) override {}
  void currentPositions(std::vector<Vec3d>& out) const override { out = mesh_.vertices; }
  bool currentSurface(TriangleMesh& out) const override {
    out = mesh_;
    return true;
  }
  MemoryReport memory() const override { return {0, mesh_.vertices.size() * sizeof(Vec3d)}; }

 private:
  TriangleMesh mesh_;
  std::size_t removed_ = 0;
};

}  // namespace inc::viewer::testing
