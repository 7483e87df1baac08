// PBD model finalisation (adjacency, Jacobi scales, colouring), validation and rest cell volumes.
#include "model/pbd_model.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/parallel.h"
#include "model/input_error.h"
#include "physics/pbd_volume.h"

namespace inc {

const char* pbdConstraintKindName(PbdConstraintKind k) {
  switch (k) {
    case PbdConstraintKind::Distance: return "distance";
    case PbdConstraintKind::Bending: return "bending";
    case PbdConstraintKind::TetVolume: return "tet_volume";
    case PbdConstraintKind::Laplacian: return "laplacian";
    case PbdConstraintKind::ShapeMatching: return "shape_matching";
  }
  return "?";
}

PbdSolverKind parsePbdSolver(const std::string& text, const std::string& file, const std::string& key) {
  if (text == "jacobi") return PbdSolverKind::Jacobi;
  if (text == "gauss_seidel" || text == "gauss-seidel" || text == "gs") return PbdSolverKind::GaussSeidel;
  throw InputError(file, key, "unknown PBD solver '" + text + "' (expected jacobi or gauss_seidel)");
}

double checkChebyshevRho(double rho, PbdSolverKind solver, const std::string& file, const std::string& key) {
  if (!(rho >= 0 && rho <= pbd::kChebyshevMaxRho))
    throw InputError(file, key,
                     "must be in [0, 0.9] (larger estimates gained energy or diverged in our tests; got " +
                         std::to_string(rho) + ")");
  if (rho > 0 && solver != PbdSolverKind::Jacobi)
    throw InputError(file, key, "accelerates the Jacobi solver only: use 0 with gauss_seidel");
  return rho;
}

namespace {
const char* kFile = "pbd model";

template <typename T>
void validateBlock(const PbdConstraintBlock<T>& b, std::size_t n, const std::string& key) {
  if (b.offsets.empty() || b.offsets.front() != 0 || std::size_t(b.offsets.back()) != b.ids.size())
    throw InputError(kFile, key + ".offsets", "offsets must start at 0 and end at the id count");
  for (std::size_t c = 0; c < b.count(); ++c) {
    const int len = b.offsets[c + 1] - b.offsets[c];
    int need = -1;
    if (b.kind == PbdConstraintKind::Distance) need = 2;
    if (b.kind == PbdConstraintKind::Bending || b.kind == PbdConstraintKind::TetVolume) need = 4;
    if ((need > 0 && len != need) || len < 1)
      throw InputError(kFile, key + "[" + std::to_string(c) + "]",
                       "wrong number of particles (" + std::to_string(len) + ")");
  }
  for (std::int32_t p : b.ids)
    if (p < 0 || std::size_t(p) >= n)
      throw InputError(kFile, key + ".ids", "particle index " + std::to_string(p) + " out of range");
  const bool scalar_rest = b.kind == PbdConstraintKind::Distance || b.kind == PbdConstraintKind::Bending ||
                           b.kind == PbdConstraintKind::TetVolume;
  if (scalar_rest && b.rest.size() != b.count())
    throw InputError(kFile, key + ".rest", "one rest value per constraint");
  if (b.kind == PbdConstraintKind::Laplacian && b.rest_vec.size() != b.count())
    throw InputError(kFile, key + ".rest_vec", "one rest Laplacian per constraint");
  if (b.kind == PbdConstraintKind::ShapeMatching && b.rest_vec.size() != b.slotCount())
    throw InputError(kFile, key + ".rest_vec", "one rest offset per cluster member");
  if (b.compliance.size() != b.multiplierCount())
    throw InputError(kFile, key + ".compliance", "one compliance per multiplier");
  for (T a : b.compliance)
    if (!(a >= T(0)) || !std::isfinite(double(a)))
      throw InputError(kFile, key + ".compliance", "must be finite and >= 0");
  if (!(b.stiffness >= T(0) && b.stiffness <= T(1))) throw InputError(kFile, key + ".stiffness", "must be in [0, 1]");
}
}  // namespace

template <typename T>
void finalizePbdModel(PbdModel<T>& model, bool coloring) {
  const std::size_t n = model.size();
  if (model.masses.size() != n || model.inv_mass.size() != n || model.rest_radii.size() != n)
    throw InputError(kFile, "particles", "masses, inverse masses and radii must have one entry per particle");
  if (!model.contact_inset.empty()) {
    if (model.contact_inset.size() != n)
      throw InputError(kFile, "contact_inset", "must have one entry per particle (or none)");
    for (std::size_t i = 0; i < n; ++i)
      if (!(model.contact_inset[i] >= T(0) && model.contact_inset[i] <= model.rest_radii[i]))
        throw InputError(kFile, "contact_inset[" + std::to_string(i) + "]", "must lie in [0, the particle's radius]");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!isFinite(model.rest_positions[i]))
      throw InputError(kFile, "rest_positions[" + std::to_string(i) + "]", "not finite");
    if (!(model.masses[i] > T(0)) || !(model.inv_mass[i] >= T(0)))
      throw InputError(kFile, "masses[" + std::to_string(i) + "]", "mass must be > 0 and inverse mass >= 0");
  }
  if (model.rotation_block >= int(model.blocks.size()) ||
      (model.rotation_block >= 0 && model.blocks[model.rotation_block].kind != PbdConstraintKind::ShapeMatching))
    throw InputError(kFile, "rotation_block", "must name a shape-matching block");
  std::vector<std::uint8_t> fixed(n);
  for (std::size_t i = 0; i < n; ++i) fixed[i] = model.inv_mass[i] == T(0) ? 1 : 0;

  for (std::size_t bi = 0; bi < model.blocks.size(); ++bi) {
    PbdConstraintBlock<T>& b = model.blocks[bi];
    const std::string key = std::string("blocks[") + std::to_string(bi) + "](" + pbdConstraintKindName(b.kind) + ")";
    validateBlock(b, n, key);
    fillParticleSlots(b, n);
    // Jacobi scale: a constraint's step is divided by the number of this block's constraints acting on its
    // busiest movable participant, so that each particle's summed correction is at most an average.
    b.jacobi_scale.assign(b.ids.size(), T(1));
    for (std::size_t c = 0; c < b.count(); ++c) {
      if (b.kind == PbdConstraintKind::ShapeMatching) {
        for (std::int32_t s = b.offsets[c]; s < b.offsets[c + 1]; ++s) {
          const std::int32_t p = b.ids[s];
          b.jacobi_scale[s] = T(1) / T(std::max(1, b.particle_offsets[p + 1] - b.particle_offsets[p]));
        }
      } else {
        int busiest = 1;
        for (std::int32_t s = b.offsets[c]; s < b.offsets[c + 1]; ++s) {
          const std::int32_t p = b.ids[s];
          if (fixed[p]) continue;
          busiest = std::max(busiest, b.particle_offsets[p + 1] - b.particle_offsets[p]);
        }
        for (std::int32_t s = b.offsets[c]; s < b.offsets[c + 1]; ++s) b.jacobi_scale[s] = T(1) / T(busiest);
      }
    }
    b.coloring = coloring ? colorConstraints(b.offsets, b.ids, n, fixed) : ConstraintColoring{};
  }
}

template <typename T>
void computeRestCellVolumes(PbdModel<T>& model, int sample_count, const std::vector<double>* known) {
  const std::size_t n = model.size();
  if (model.overlap_offsets.size() != n + 1 || std::size_t(model.overlap_offsets.back()) != model.overlap_ids.size())
    throw InputError(kFile, "overlap_offsets", "must hold one list per sphere");
  if (sample_count < 8) throw InputError(kFile, "volume samples", "need at least 8 samples per sphere");
  model.ball_samples.resize(std::size_t(sample_count));
  for (int k = 0; k < sample_count; ++k) model.ball_samples[k] = Vec3<T>(pbd::unitBallSample<double>(k, sample_count));
  model.rest_cell_volume.assign(n, T(0));
  // Independent per sphere (each writes its own entry): on the CPU fallback's threads, since a cut rebuilds the
  // model every frame the blade enters spheres and this is the largest part of a rebuild.
  cpu::parallelFor(std::int64_t(n), [&](std::int64_t i) {
    if (known && !std::isnan((*known)[std::size_t(i)])) {  // the caller's value for an unchanged neighbourhood
      model.rest_cell_volume[i] = T((*known)[std::size_t(i)]);
      return;
    }
    const std::int32_t b = model.overlap_offsets[i], e = model.overlap_offsets[i + 1];
    model.rest_cell_volume[i] = pbd::powerCellVolume(
        model.rest_positions[i], model.rest_radii[i], model.rest_positions.data(), model.rest_radii.data(),
        model.overlap_ids.data() + b, e - b, model.ball_samples.data(), sample_count);
  });
}

template void finalizePbdModel<float>(PbdModel<float>&, bool);
template void finalizePbdModel<double>(PbdModel<double>&, bool);
template void computeRestCellVolumes<float>(PbdModel<float>&, int, const std::vector<double>*);
template void computeRestCellVolumes<double>(PbdModel<double>&, int, const std::vector<double>*);

}  // namespace inc
