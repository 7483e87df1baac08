// The CPU's MLS stress and force passes over a range of particles with the rest pair tables: the sums of
// physics/mls_passes.h, vectorised with AVX2 when the CPU has it (run-time check), the same result bit for bit.
#pragma once

#include <cstdint>

#include "physics/mls_passes.h"

namespace inc::cpu {

// Whether float passes use the AVX2 loops: the CPU has AVX2 and the portable loops are not forced.
bool mlsPairSumsUseAvx2();
// Forces the portable loops (tests compare the two paths; the default uses AVX2 where the CPU has it).
void setMlsPairSumsPortable(bool portable_only);

// mlsStressPass for every particle in [begin, end) of a view with pair tables.
template <typename T>
void mlsStressRange(const MlsView<T>& s, std::int64_t begin, std::int64_t end, bool avx2);
// mlsForcePass for every particle in [begin, end) of a view with pair tables.
template <typename T>
void mlsForceRange(const MlsView<T>& s, std::int64_t begin, std::int64_t end, T half_dt, bool kick, bool avx2);

}  // namespace inc::cpu
