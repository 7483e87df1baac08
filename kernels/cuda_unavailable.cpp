// Built instead of the CUDA sources when nvcc is absent: reports that this binary has no GPU backend.
#include "kernels/device_info.h"

namespace inc::cuda {

DeviceReport queryDevices() {
  DeviceReport r;
  r.compiled = false;
  r.error = "this build of Incision was configured without CUDA (nvcc not found)";
  return r;
}

double measureCopyBandwidthGbs() { return 0.0; }

}  // namespace inc::cuda
