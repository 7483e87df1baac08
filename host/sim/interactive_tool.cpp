// The mouse tool's shared logic: PBD grasp targets, blades from tool events, rest points, link components.
#include "host/sim/interactive_tool.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

#include "model/input_error.h"

namespace inc {

namespace {
constexpr double kGraspCompliance = 1.0e-6;  // m/N, as the scripted grasper (host/sim/metaball_simulation.cpp)
}

ToolResult PbdMouseGrasp::apply(const ToolEvent& e, const std::vector<Vec3d>& centres, const std::vector<double>& radii,
                                const std::vector<std::uint8_t>& movable) {
  ToolResult r;
  r.supported = true;
  if (!isFinite(e.tip)) throw InputError("tool", "tip", "must be finite");
  switch (e.phase) {
    case ToolPhase::Press: {
      release();
      if (!(e.radius_m > 0) || !std::isfinite(e.radius_m)) throw InputError("tool", "radius_m", "must be > 0");
      ToolSpec spec;
      spec.name = "mouse";
      spec.kind = "grasper";
      spec.radius = e.radius_m;
      spec.path = {{0.0, e.tip, e.axis}};
      grasper_.emplace(spec, e.radius_m, kGraspCompliance);
      grasper_->grasp(e.tip, centres, radii, movable);
      from_ = to_ = e.tip;
      if (!grasper_->holding()) r.message = "nothing within reach of the tip";
      break;
    }
    case ToolPhase::Drag:
      if (holding()) to_ = e.tip;
      break;
    case ToolPhase::Release: release(); break;
  }
  r.grasped = held();
  return r;
}

void PbdMouseGrasp::release() { grasper_.reset(); }

BladePose bladeFromToolEvent(const ToolEvent& e) {
  if (!isFinite(e.tip) || !isFinite(e.axis)) throw InputError("tool", "blade", "tip and axis must be finite");
  const double n = norm(e.axis);
  if (!(n > 0)) throw InputError("tool", "axis", "must not be zero");
  if (!(e.blade_length_m > 0) || !std::isfinite(e.blade_length_m))
    throw InputError("tool", "blade_length_m", "must be > 0");
  const Vec3d half = e.axis * (0.5 * e.blade_length_m / n);
  return {e.tip - half, e.tip + half};
}

Vec3d restPointFromCurrent(const Vec3d& p, const std::vector<Vec3d>& current, const std::vector<Vec3d>& rest, int k) {
  const std::size_t n = std::min(current.size(), rest.size());
  if (n == 0) return p;
  const std::size_t m = std::min<std::size_t>(std::size_t(std::max(k, 1)), n);
  std::vector<std::pair<double, std::size_t>> d(n);
  for (std::size_t i = 0; i < n; ++i) d[i] = {norm2(current[i] - p), i};
  std::partial_sort(d.begin(), d.begin() + std::ptrdiff_t(m), d.end());
  Vec3d u;
  double wsum = 0;
  const double eps = 1e-9;  // m: a point on a particle takes that particle's displacement
  for (std::size_t j = 0; j < m; ++j) {
    const double w = 1.0 / (std::sqrt(d[j].first) + eps);
    u += (current[d[j].second] - rest[d[j].second]) * w;
    wsum += w;
  }
  return p - u * (1.0 / wsum);
}

}  // namespace inc
