// Compulsory memory traffic of the MLS solver (bytes): one substep and the per-frame reduction (bench_mls,
// bench_scaling).
#pragma once

#include <cstddef>
#include <cstdint>

namespace inc::bench {

// One substep, each array touched once per pass and neighbour indices once per pass: a lower bound on bytes
// moved; with perfect caching of neighbour data the kernels reach it. n particles, nnz neighbour entries, t
// bytes per scalar (4 float32, 8 float64).
inline double mlsStepBytes(std::int64_t n, double nnz, std::size_t t) {
  const double T = double(t), N = double(n);
  const double drift = N * (1 + 10 * T + 6 * T);  // kind, v, f, m, u read; v, u written
  const double stress = N * (3 * T + 3 * T + 9 * T + T + 8 + 9 * T + T) + nnz * 4;  // X, u, A^-1, v, offsets; M, psi
  const double force =
      N * (3 * T + 9 * T + 8 + 1 + T + 3 * T + 3 * T + 3 * T) + nnz * 4;  // X, M, offsets, kind, m, v, f
  return drift + stress + force;
}

// The once-per-frame reduction (energies, max displacement, finiteness, and the deformation-aware step, which
// recomputes each particle's gradient): m, v, u, f, psi read, and X, A^-1, offsets, indices for the gradient.
inline double mlsFrameReductionBytes(std::int64_t n, double nnz, std::size_t t) {
  const double T = double(t);
  return double(n) * (T + 3 * T + 3 * T + 3 * T + T + 3 * T + 9 * T + 8) + nnz * 4;
}

// A whole frame of `substeps` substeps.
inline double mlsFrameBytes(std::int64_t n, double nnz, std::size_t t, int substeps) {
  return double(substeps) * mlsStepBytes(n, nnz, t) + mlsFrameReductionBytes(n, nnz, t);
}

}  // namespace inc::bench
