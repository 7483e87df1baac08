// The macros of shared physics math: INC_HD marks it callable from host and device code; INC_UNROLL asks the
// device compiler to unroll a loop of constant trip count (so that a small array's indices become constants and
// the array lives in registers; host compilers decide for themselves).
#pragma once

#if defined(__CUDACC__)
#define INC_HD __host__ __device__ __forceinline__
#else
#define INC_HD inline
#endif

#if defined(__CUDA_ARCH__)
#define INC_UNROLL _Pragma("unroll")
#else
#define INC_UNROLL
#endif
