// Thread-count query for the CPU fallback.
#include "base/parallel.h"

#include <omp.h>

namespace inc::cpu {

int threadCount() { return omp_get_max_threads(); }

}  // namespace inc::cpu
