// A tearable triangle sheet: particles, triangles, derived bond/triangle adjacency, PBD model assembly, removal tools
// and mesh checks.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "model/pbd_model.h"
#include "physics/vec3.h"

namespace inc {

// How bonds break (docs/tearing.md).
enum class TearCriterion : int {
  Threshold = 0,        // traditional PBD tearing: a bond strain past break_strain splits the vertex, t = 0
  TrescaBonds = 1,      // eq. 6 on the particle's largest and smallest bond strains, debris at fraction t
  TrescaPrincipal = 2,  // eq. 5 on the principal stresses of the particle's bond stress tensor
};
const char* tearCriterionName(TearCriterion c);
// "traditional" | "threshold" | "tresca" | "tresca_principal"; InputError naming `key` otherwise.
TearCriterion parseTearCriterion(const std::string& text, const std::string& file, const std::string& key);

template <typename T>
struct TearParams {
  TearCriterion criterion = TearCriterion::TrescaBonds;
  T break_strain = T(0.5);  // Threshold: bond strain at which a bond breaks
  T random_range = T(0.1);  // the paper's 10 %: t (1 + range u), u in [-1, 1)
  T t_lo = T(0.05), t_hi = T(0.95);
  T min_area_ratio = T(0.1);  // a moved triangle must keep this fraction of its area, same orientation
  std::uint32_t seed = 1;
};

// Axis-aligned region with its own material (the paper: k and tau_f per body part).
struct TearRegion {
  Vec3d min, max;
  double k_pa = 0.0, tau_f_pa = 0.0;
};

template <typename T>
struct TearSheet {
  // Per particle (SoA).
  std::vector<Vec3<T>> rest;  // m, rest positions: every rest length and rest angle comes from these
  std::vector<Vec3<T>> x, v;  // m, m/s
  std::vector<T> mass;        // kg (lumped area mass)
  std::vector<std::uint8_t> fixed;
  std::vector<T> k, tau_f;  // Pa: eq. 6 modulus and yield shear stress
  // Per triangle: counter-clockwise about ref_normal (the rest normal when it was made; never flips).
  std::vector<std::array<std::int32_t, 3>> tris;
  std::vector<Vec3<T>> ref_normal;

  // Derived by rebuildTopology(): unique bonds (mesh edges, a < b, sorted), particle -> bond partners
  // (ascending partner index) and particle -> triangles (ascending triangle index).
  std::vector<std::int32_t> edge_a, edge_b;
  std::vector<std::int32_t> pe_offsets, pe_partner;
  std::vector<std::int32_t> pt_offsets, pt_tris;
  std::uint32_t step = 0;  // tearing steps taken (the random stream's counter)

  std::size_t size() const { return x.size(); }
  // Every per-particle array to m entries (new particles appended by a split; both backends fill them).
  void resizeParticles(std::size_t m) {
    rest.resize(m);
    x.resize(m);
    v.resize(m);
    mass.resize(m);
    fixed.resize(m);
    k.resize(m);
    tau_f.resize(m);
  }
  void rebuildTopology();
};

// A flat nx x ny grid of particles (spacing h) in the plane z = z0 starting at origin, triangulated with
// alternating diagonals, normals +z. Area density rho_a (kg/m^2) gives lumped masses.
template <typename T>
TearSheet<T> makeTearGrid(int nx, int ny, double h, double rho_a, const Vec3d& origin, double k_pa, double tau_f_pa);

// An open tube (a leg's skin): n_around x n_along particles on a cylinder of radius r about the z axis
// from z = 0 to length, normals outward.
template <typename T>
TearSheet<T> makeTearTube(int n_around, int n_along, double radius, double length, double rho_a, double k_pa,
                          double tau_f_pa);

// Sets k and tau_f of particles whose rest position lies in a region (later regions win).
template <typename T>
void applyTearRegions(TearSheet<T>& s, const std::vector<TearRegion>& regions);
// Fixes particles whose rest position lies in the box.
template <typename T>
void fixTearParticles(TearSheet<T>& s, const Vec3d& lo, const Vec3d& hi);

struct TearModelOptions {
  double stretch_compliance = 0.0;  // m/N (XPBD)
  double bending_compliance = 1.0;  // rad/(N m)
  double pbd_stiffness = 1.0;
  // false: skip the Gauss-Seidel colouring (the Jacobi solver does not read it) and derive the particle ->
  // slot lists and Jacobi scales here exactly as finalizePbdModel does; a tearing frame rebuilds the model.
  bool coloring = true;
  // CUDA device-resident path (docs/tearing.md): re-derive the adjacency and the constraint blocks after a
  // tearing step by the older radix-sort rebuild instead of the per-particle one (same arrays; to compare).
  bool device_sorted_rebuild = false;
};
// Distance block on every bond, Bending block on every edge shared by exactly two triangles, rest values
// from the rest positions; fixed particles get inverse mass 0. Finalised.
template <typename T>
PbdModel<T> buildTearPbdModel(const TearSheet<T>& s, const TearModelOptions& opt);

// Validity after topology changes: every count must be 0 for a valid mesh.
struct TearMeshCheck {
  int dead_refs = 0;           // triangle index out of range, or a particle without triangles
  int degenerate = 0;          // repeated index, or rest area below 1e-6 of the mean
  int inverted = 0;            // rest area vector against the triangle's reference normal
  int inverted_current = 0;    // current area vector against the reference normal (info: folds are legal)
  int duplicates = 0;          // two triangles with the same vertex set
  int non_manifold_edges = 0;  // edges in more than two triangles
  int inconsistent_edges = 0;  // interior edges traversed the same way by both triangles
  bool valid() const {
    return dead_refs == 0 && degenerate == 0 && inverted == 0 && duplicates == 0 && non_manifold_edges == 0 &&
           inconsistent_edges == 0;
  }
};
template <typename T>
TearMeshCheck checkTearMesh(const TearSheet<T>& s);

// Sum of the lengths of edges with exactly one triangle (rest or current configuration), m.
template <typename T>
double tearBoundaryLength(const TearSheet<T>& s, bool rest_config);

template <typename T>
double totalMass(const TearSheet<T>& s);
template <typename T>
Vec3d totalMomentum(const TearSheet<T>& s);

// Removes tissue: particles with mark[i] != 0. Traditional: they, their triangles and particles left
// without triangles go. debris == true (Tresca): marked particles with an unmarked bond partner stay as debris,
// moved to x_k + t (x_r - x_k) of their lowest-index unmarked partner k (t the seeded fraction around 1/2),
// triangles without any unmarked vertex go. Compacts particles and triangles; returns particles removed.
// remap (optional) receives old index -> new index (-1 when removed).
template <typename T>
int removeTearParticles(TearSheet<T>& s, const std::vector<std::uint8_t>& mark, bool debris, const TearParams<T>& p,
                        std::vector<std::int32_t>* remap = nullptr);

// Marks: rest position inside the box / within `radius` of the segment a-b (current positions).
template <typename T>
std::vector<std::uint8_t> markInBox(const TearSheet<T>& s, const Vec3d& lo, const Vec3d& hi);
template <typename T>
std::vector<std::uint8_t> markNearSegment(const TearSheet<T>& s, const Vec3d& a, const Vec3d& b, double radius);

}  // namespace inc
