// The process-wide lock that keeps CUDA graph captures and device loads on worker threads apart.
#pragma once

#include <mutex>

namespace inc {

// A stream capture (kernels/graph_capture.h) holds it from its begin to its end; a model loaded into spare device
// buffers on a worker thread while the frame goes on (a cut's next PBD model and MLS solver) holds it for the load.
// The load's allocations, frees, device-wide wait and legacy-stream copies would otherwise join or break a capture
// that the frame's thread has open (cudaErrorStreamCaptureImplicit and kin). Inline: one mutex in the program,
// whichever library (host/, kernels/) takes it.
inline std::mutex& deviceCaptureMutex() {
  static std::mutex m;
  return m;
}

}  // namespace inc
