// The interface every simulated model (MLS solid, metaball organ, tearing sheet, ...) offers the runner.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "host/backend.h"
#include "host/mesh.h"
#include "physics/vec3.h"

namespace inc {

struct StageTime {
  std::string stage;  // a name from the paper's loop: "gradients", "stress", "forces", "integrate", ...
  double ms = 0.0;    // wall time of the stage summed over the frame's substeps (device events on the GPU)
};

// What one frame did; the runner writes it as a row of metrics.csv and checks it.
struct FrameReport {
  int substeps = 0;
  double dt = 0.0;                   // s, substep actually used
  std::vector<StageTime> stages;
  double kinetic_energy = 0.0;       // J
  double elastic_energy = 0.0;       // J (strain or constraint energy)
  double potential_energy = 0.0;     // J, gravity, relative to rest
  double max_displacement = 0.0;     // m, from rest
  bool finite = true;                // false: a NaN/Inf appeared; failure_* say where
  std::string failure_stage;
  std::int64_t failure_particle = -1;
  std::map<std::string, double> counters;  // model-specific ("degenerate_neighbourhoods", "broken_bonds", ...)
};

struct MemoryReport {
  std::size_t device_bytes = 0;
  std::size_t host_bytes = 0;
};

class SimulationModel {
 public:
  virtual ~SimulationModel() = default;
  virtual std::string name() const = 0;
  virtual BackendKind backend() const = 0;
  virtual std::size_t particleCount() const = 0;
  // Advances one frame of frame_dt seconds, substepping as stability requires. Must not throw on bad
  // physics: report finite == false with the stage and particle instead.
  virtual FrameReport advance(double frame_dt) = 0;
  // Keep / return to the last good state (the runner's guard rolls back and retries with a smaller step).
  virtual void saveCheckpoint() = 0;
  virtual void restoreCheckpoint() = 0;
  // Scale the stable-step safety factor (the guard halves it on a retry).
  virtual void scaleTimeStep(double factor) = 0;
  // Current particle positions (for output and drawing) and the surface, if the model has one.
  virtual void currentPositions(std::vector<Vec3d>& out) const = 0;
  virtual bool currentSurface(TriangleMesh& /*out*/) const { return false; }
  virtual MemoryReport memory() const = 0;
};

}  // namespace inc
