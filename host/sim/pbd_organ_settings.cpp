// The PBD organ's scene settings (pbdOrganParams, pbdOrganOptions): one translation for both PBD organ models.
#include "host/sim/pbd_organ_settings.h"

namespace inc {

template <typename T>
PbdStepParams<T> pbdOrganParams(const CompiledScene& scene) {
  const std::string& f = scene.file;
  PbdStepParams<T> p;
  p.solver = parsePbdSolver(scene.pbd.solver, f, "pbd.solver");
  p.iterations = scene.pbd.iterations;
  p.chebyshev_rho = T(checkChebyshevRho(scene.pbd.chebyshev_rho, p.solver, f, "pbd.chebyshev_rho"));
  // CUDA single-block fused frame: measured on an H100 (docs/BENCHMARKS.md) it beats per-phase launches for
  // Gauss-Seidel up to thousands of spheres, but for Jacobi only below ~300 spheres; on sm_90 Jacobi models of up
  // to cluster_max_particles run the thread-block cluster frame instead (faster still, docs/pbd.md).
  p.fused_max_particles = p.solver == PbdSolverKind::Jacobi ? 256 : 4096;
  p.xpbd = scene.pbd.xpbd;
  p.gravity = Vec3<T>(scene.solver.gravity);
  p.damping = T(scene.material.damping_per_s);
  p.volume_preservation = scene.pbd.volume_preservation;
  p.volume_influence = T(2.0 * scene.geometry.spacing);
  return p;
}

MetaballPbdOptions pbdOrganOptions(const CompiledScene& scene) {
  MetaballPbdOptions opt;
  opt.youngs_modulus_pa = scene.material.youngs_modulus_pa;
  opt.stretch_compliance = scene.pbd.stretch_compliance;
  opt.laplacian_compliance = scene.pbd.laplacian_compliance;
  opt.fixed = scene.fixed;
  opt.colliders = scene.colliders;
  opt.file = scene.file;
  opt.volume_samples = scene.pbd.volume_preservation ? 64 : 0;
  return opt;
}

template PbdStepParams<float> pbdOrganParams<float>(const CompiledScene&);
template PbdStepParams<double> pbdOrganParams<double>(const CompiledScene&);

}  // namespace inc
