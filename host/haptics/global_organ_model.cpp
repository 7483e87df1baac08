// Global organ model: precompute (BEM inverse, per-element hybrid contact table) with the cache, the tools'
// coupled stiffness on their haptic threads, the organ's surface displacement once per frame.
#include "host/haptics/global_organ_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "base/progress.h"
#include "host/haptics/hybrid_model.h"
#include "model/input_error.h"

namespace inc {

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One progress bar over the precompute's phases, each a share of the bar.
class PhaseBar {
 public:
  PhaseBar(const std::string& label, bool quiet) : bar_(label, 1000, quiet) {}
  // The next phase: [from, to) of the bar, named `what`.
  BemModel::Progress phase(double from, double to, std::string what) {
    return [this, from, to, what = std::move(what)](double f) {
      bar_.update(long(1000.0 * (from + (to - from) * std::clamp(f, 0.0, 1.0))), what);
    };
  }
  void finish(const std::string& extra) { bar_.finish(extra); }

 private:
  Progress bar_;
};

// For every element: the coupled tool stiffness and the organ's surface response (a held element: the local
// model alone, no response).
OrganContactTable contactTable(BemModel& bem, const std::vector<BemBc>& supports, const HemisphereCloudSpec& local,
                               const Material& material, const BemModel::Progress& progress) {
  const int E = bem.elementCount();
  OrganContactTable t;
  t.stiffness = Eigen::MatrixXd::Zero(9, E);
  t.surface = Eigen::MatrixXd::Zero(3 * E, 3 * E);
  HybridHapticModel hybrid(bem, local, material);
  for (int e = 0; e < E; ++e) {
    Eigen::Matrix3d k;
    if (supports[std::size_t(e)] == BemBc::kDisplacement) {
      k = hybrid.worldLocalOnlyStiffness(e);
    } else {
      hybrid.touch(e);
      k = hybrid.worldToolStiffness();
      t.surface.middleCols(3 * e, 3) = hybrid.worldSurfaceCompliance();
    }
    t.stiffness.col(e) = Eigen::Map<const Eigen::VectorXd>(k.data(), 9);
    if (progress && (e % 8 == 7 || e + 1 == E)) progress(double(e + 1) / E);
  }
  return t;
}

}  // namespace

GlobalOrganModel::GlobalOrganModel(GlobalOrganSetup setup, int hands) : mesh_(std::move(setup.mesh)) {
  const int E = elementCount();
  if (E < 4) throw InputError("<global organ model>", "mesh", "needs a closed mesh of at least 4 triangles");
  if (setup.supports.size() != mesh_.triangles.size())
    throw InputError("<global organ model>", "supports", "need one condition per element");
  if (hands < 1) throw InputError("<global organ model>", "hands", "needs at least one tool");
  for (const auto& t : mesh_.triangles)
    centroids_.push_back(
        (mesh_.vertices[std::size_t(t[0])] + mesh_.vertices[std::size_t(t[1])] + mesh_.vertices[std::size_t(t[2])]) *
        (1.0 / 3.0));
  build(setup);
  for (int k = 0; k < hands; ++k) channels_.push_back(std::make_unique<TripleBuffer<OrganContact>>());
  u_ = Eigen::VectorXd::Zero(3 * E);
}

void GlobalOrganModel::build(const GlobalOrganSetup& s) {
  const auto t0 = std::chrono::steady_clock::now();
  const BemCacheKey key = bemCacheKey(mesh_, s.supports, s.material, s.local.radius_m, s.local.inner_spacing_m);
  Eigen::MatrixXd a_inv;
  BemCacheRead cached;
  if (!s.cache_path.empty())
    cached = readBemCache(s.cache_path, key, table_, a_inv);
  else
    cached.note = "no cache file";
  if (cached.table) {
    precompute_.source = "loaded from the cache";
    precompute_.seconds = secondsSince(t0);
    return;
  }
  precompute_.note = cached.note;
  PhaseBar bar(s.label + " (" + std::to_string(elementCount()) + " elements)", s.quiet);
  const double table_from = cached.inverse ? 0.3 : 0.55;
  auto t = std::chrono::steady_clock::now();
  BemModel bem(mesh_, s.material, bar.phase(0.0, cached.inverse ? table_from : 0.15, "assembling H, G"));
  precompute_.assembly_s = secondsSince(t);
  t = std::chrono::steady_clock::now();
  if (cached.inverse)
    bem.setBaseInverse(s.supports, std::move(a_inv));
  else
    bem.factorBase(s.supports, bar.phase(0.15, table_from, "inverting A"));
  precompute_.inverse_s = secondsSince(t);
  t = std::chrono::steady_clock::now();
  table_ = contactTable(bem, s.supports, s.local, s.material, bar.phase(table_from, 1.0, "contact table"));
  precompute_.table_s = secondsSince(t);
  precompute_.source = cached.inverse ? "table rebuilt from the cached inverse" : "built";
  if (!s.cache_path.empty()) {
    try {
      writeBemCache(s.cache_path, key, table_, bem.baseInverse());
    } catch (const InputError& e) {
      precompute_.note += "; not cached: " + e.reason();
    }
  }
  bar.finish(precompute_.source);
  precompute_.seconds = secondsSince(t0);
}

int GlobalOrganModel::nearestElement(const Vec3d& p) const {
  int best = 0;
  double d2 = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < centroids_.size(); ++j) {
    const double d = norm2(centroids_[j] - p);
    if (d < d2) {
      d2 = d;
      best = int(j);
    }
  }
  return best;
}

CuttingTool::Elastic GlobalOrganModel::contactElastic(int hand) {
  if (hand < 0 || hand >= int(channels_.size())) throw InputError("<global organ model>", "hand", "out of range");
  TripleBuffer<OrganContact>* channel = channels_[std::size_t(hand)].get();
  // Haptic-thread state of this hand: the anchor whose element is known.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return [this, channel, anchor = Vec3d{nan, nan, nan}, element = -1](const TipContact& c) mutable {
    ForceResult r;
    OrganContact& out = channel->back();
    out = OrganContact{};
    if (c.in_contact) {
      if (!(c.anchor_m.x == anchor.x && c.anchor_m.y == anchor.y && c.anchor_m.z == anchor.z)) {
        anchor = c.anchor_m;
        element = nearestElement(anchor);
      }
      const Eigen::Map<const Eigen::Matrix3d> k(table_.stiffness.col(element).data());
      const Vec3d& d = c.displacement_m;
      const Eigen::Vector3d f = k * Eigen::Vector3d(d.x, d.y, d.z);  // on the organ
      out.in_contact = true;
      out.element = element;
      out.tip_displacement_m = d;
      out.organ_force_n = {f[0], f[1], f[2]};
      r.force_n = out.organ_force_n * -1.0;  // the tissue pushes back on the hand
    }
    channel->publish();
    return r;
  };
}

void GlobalOrganModel::step() {
  const auto t0 = std::chrono::steady_clock::now();
  u_.setZero();
  contacts_ = 0;
  for (auto& ch : channels_) {
    ch->update();
    const OrganContact& c = ch->front();
    if (!c.in_contact) continue;
    ++contacts_;
    u_ += table_.surface.middleCols(3 * c.element, 3) *
          Eigen::Vector3d(c.organ_force_n.x, c.organ_force_n.y, c.organ_force_n.z);
  }
  // The half-space field is singular at a contact element: it follows its tool instead.
  for (auto& ch : channels_) {
    const OrganContact& c = ch->front();
    if (c.in_contact)
      u_.segment<3>(3 * c.element) << c.tip_displacement_m.x, c.tip_displacement_m.y, c.tip_displacement_m.z;
  }
  max_u_ = 0.0;
  for (int j = 0; j < elementCount(); ++j) max_u_ = std::max(max_u_, u_.segment<3>(3 * j).norm());
  peak_u_ = std::max(peak_u_, max_u_);
  ++steps_;
  last_step_s_ = secondsSince(t0);
}

TriangleMesh GlobalOrganModel::deformedMesh() const {
  TriangleMesh out = mesh_;
  std::vector<Vec3d> sum(mesh_.vertices.size());
  std::vector<int> count(mesh_.vertices.size(), 0);
  for (std::size_t j = 0; j < mesh_.triangles.size(); ++j)
    for (int v : mesh_.triangles[j]) {
      sum[std::size_t(v)] += Vec3d{u_[Eigen::Index(3 * j)], u_[Eigen::Index(3 * j + 1)], u_[Eigen::Index(3 * j + 2)]};
      ++count[std::size_t(v)];
    }
  for (std::size_t v = 0; v < out.vertices.size(); ++v)
    if (count[v] > 0) out.vertices[v] += sum[v] * (1.0 / count[v]);
  return out;
}

std::string GlobalOrganModel::summary() const {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "global model bem: %d elements (%d DOFs), %s, precompute %.2f s; %llu steps (one per frame), last "
                "step %.1f us, organ surface max displacement %.3g m now, %.3g m at most",
                elementCount(), 3 * elementCount(), precompute_.source.c_str(), precompute_.seconds,
                static_cast<unsigned long long>(steps_), 1e6 * last_step_s_, max_u_, peak_u_);
  std::string out = buf;
  if (!precompute_.note.empty()) out += " (" + precompute_.note + ")";
  return out;
}

}  // namespace inc
