// The one macro that marks shared physics math as callable from host and device code.
#pragma once

#if defined(__CUDACC__)
#define INC_HD __host__ __device__ __forceinline__
#else
#define INC_HD inline
#endif
