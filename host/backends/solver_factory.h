// Creating the solvers' backends: the CPU fallback or CUDA, per the resolved backend kind.
#pragma once

#include <memory>

#include "model/backend.h"
#include "model/mls_solver.h"
#include "model/pbd_model.h"
#include "model/tear_step.h"

namespace inc {

// CPU or CUDA per `kind` (Auto resolves as resolveBackend does).
template <typename T>
std::unique_ptr<PbdBackend<T>> makePbdBackend(BackendKind kind);

// Builds the model in the requested precision and the solver on the requested backend (Auto resolves
// to CUDA when usable). Throws InputError for bad input or an unavailable backend.
std::unique_ptr<MlsSolver> makeMlsSolver(const MlsBuildInput& input, BackendKind backend, Precision precision);

// A model built in the precision its solver runs, apart from loading it: a cut builds the next model on a worker
// (host work, rest configuration only) while the current solver runs, and loads it later (loadMlsSolver).
struct MlsBuiltModel {
  Precision precision = Precision::Float32;
  MlsModel<float> f32;  // the one of `precision`; the other stays empty
  MlsModel<double> f64;
};
MlsBuiltModel buildMlsModelIn(const MlsBuildInput& input, Precision precision);

// `solver` on `model` (moved from): replaced in place when it is a solver of that backend and precision that
// reuses its resources (replaceModel), else a new one. Throws InputError for an unavailable backend.
void loadMlsSolver(std::unique_ptr<MlsSolver>& solver, MlsBuiltModel& model, BackendKind backend);

// buildMlsModelIn then loadMlsSolver. The same errors as makeMlsSolver. `build_ms`, when given, receives the host
// time of the model build alone (the rest is the solver's load).
void rebuildMlsSolver(std::unique_ptr<MlsSolver>& solver, const MlsBuildInput& input, BackendKind backend,
                      Precision precision, double* build_ms = nullptr);

// The tearing step on CPU or CUDA per `kind` (Auto resolves as resolveBackend does).
template <typename T>
std::unique_ptr<TearStepBackend<T>> makeTearStepBackend(BackendKind kind);

}  // namespace inc
