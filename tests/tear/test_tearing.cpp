// Tearing sheet tests: yield below/above eq. 6, split placement, conservation, mesh validity over thousands of splits,
// reproducibility, roughness.
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>

#include "cpu_fallback/tearing_cpu.h"
#include "host/tear/tearing_driver.h"
#include "model/input_error.h"
#include "model/tearing_sheet.h"
#include "physics/pbd_constraints.h"
#include "physics/tearing_tresca.h"
#include "tests/support/tolerance.h"

using namespace inc;

namespace {

// Skin-like sheet: 2.2 kg/m^2 (1100 kg/m^3, 2 mm), spacing 1 cm.
constexpr double kH = 0.01, kRhoA = 2.2, kK = 1.0e4;

// Eq. 6 computed independently of the library's detection (for cross-checking).
double maxShearOf(const TearSheet<double>& s, std::size_t i, std::int32_t* partner = nullptr) {
  double rmax = -1e300, rmin = 1e300;
  for (std::int32_t q = s.pe_offsets[i]; q < s.pe_offsets[i + 1]; ++q) {
    const std::int32_t j = s.pe_partner[q];
    const double rho = (norm(s.x[i] - s.x[j]) - norm(s.rest[i] - s.rest[j])) / norm(s.rest[i] - s.rest[j]);
    if (rho > rmax) {
      rmax = rho;
      if (partner) *partner = j;
    }
    rmin = std::min(rmin, rho);
  }
  return std::fabs(s.k[i] * rmax - s.k[i] * rmin) / 2;
}

double maxShear(const TearSheet<double>& s) {
  double m = 0;
  for (std::size_t i = 0; i < s.size(); ++i) m = std::max(m, maxShearOf(s, i));
  return m;
}

PbdStepParams<double> quietStep() {
  PbdStepParams<double> p;
  p.gravity = Vec3d(0, 0, 0);
  p.substeps = 4;
  p.iterations = 8;
  p.damping = 4.0;
  p.volume_preservation = false;
  return p;
}

TearModelOptions softSkin() {
  TearModelOptions o;
  o.stretch_compliance = 2e-4;  // m/N per bond
  o.bending_compliance = 10.0;
  return o;
}

// Pulls the right column of a 10 x 5 sheet (left column fixed) by `pull` m along x over 5 frames, holds 3,
// releases for `release` frames. Returns the largest eq. 6 shear seen and the splits made.
struct PullResult {
  double max_shear = 0;
  int splits = 0;
  double max_rest_error = 0;  // after release, m
};
PullResult pullAndRelease(double tau, double pull, int release, TearCriterion crit = TearCriterion::TrescaBonds) {
  TearSheet<double> s = makeTearGrid<double>(10, 5, kH, kRhoA, Vec3d(0, 0, 0), kK, tau);
  fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1e-3, 1, 1));
  std::vector<std::int32_t> grasp;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.rest[i].x > 0.089) grasp.push_back(std::int32_t(i));
  TearParams<double> tp;
  tp.criterion = crit;
  tp.break_strain = tau / kK;
  TearingDriver<double> d(s, tp, softSkin(), quietStep(), BackendKind::Cpu);
  PullResult r;
  for (int f = 0; f < 8; ++f) {
    std::vector<Vec3d> to;
    for (std::int32_t id : grasp) to.push_back(d.sheet().rest[id] + Vec3d(pull * std::min(1.0, (f + 1) / 5.0), 0, 0));
    // Grasped ids stay valid: splits only append particles.
    const TearFrameStats st = d.advance(grasp, to);
    r.splits += st.splits;
    r.max_shear = std::max(r.max_shear, maxShear(d.sheet()));
  }
  for (int f = 0; f < release; ++f) r.splits += d.advance({}, {}).splits;
  for (std::size_t i = 0; i < d.sheet().size(); ++i)
    r.max_rest_error = std::max(r.max_rest_error, norm(d.sheet().x[i] - d.sheet().rest[i]));
  return r;
}

void expectValid(const TearSheet<double>& s) {
  const TearMeshCheck c = checkTearMesh(s);
  EXPECT_EQ(c.dead_refs, 0);
  EXPECT_EQ(c.degenerate, 0);
  EXPECT_EQ(c.inverted, 0);
  EXPECT_EQ(c.duplicates, 0);
  EXPECT_EQ(c.non_manifold_edges, 0);
  EXPECT_EQ(c.inconsistent_edges, 0);
}

// The principal-stress criterion's shear at particle i computed by hand: the in-plane bond stress tensor
// sigma = (1/n) sum_b k rho_b n_b n_b^T of a flat sheet (z = 0), its two principal stresses in closed form, and
// Tresca over all three principal stresses, the third being the out-of-plane 0 of plane stress:
// tau = (max(s_a, s_b, 0) - min(s_a, s_b, 0)) / 2.
double planeStressTresca(const TearSheet<double>& s, std::size_t i) {
  double sxx = 0, syy = 0, sxy = 0;
  const int n = s.pe_offsets[i + 1] - s.pe_offsets[i];
  for (std::int32_t q = s.pe_offsets[i]; q < s.pe_offsets[i + 1]; ++q) {
    const std::int32_t j = s.pe_partner[q];
    const double rest = norm(s.rest[i] - s.rest[j]), len = norm(s.x[j] - s.x[i]);
    const double stress = s.k[i] * (len - rest) / rest;
    const double nx = (s.x[j].x - s.x[i].x) / len, ny = (s.x[j].y - s.x[i].y) / len;
    sxx += stress * nx * nx / n;
    syy += stress * ny * ny / n;
    sxy += stress * nx * ny / n;
  }
  const double mean = 0.5 * (sxx + syy), radius = std::hypot(0.5 * (sxx - syy), sxy);
  const double sa = mean + radius, sb = mean - radius;
  return (std::max({sa, sb, 0.0}) - std::min({sa, sb, 0.0})) / 2;
}

}  // namespace

TEST(Tearing, BelowYieldNothingBreaksAndReleasedSheetReturnsToRest) {
  const PullResult probe = pullAndRelease(1e30, 0.006, 0);  // measures the shear a 6 mm pull causes
  ASSERT_GT(probe.max_shear, 10.0);                         // the pull does stress the sheet (Pa)
  const PullResult below = pullAndRelease(1.5 * probe.max_shear, 0.006, 150);
  EXPECT_EQ(below.splits, 0);
  // Released and damped (4/s over 2.5 s): back at rest within 0.1 mm.
  EXPECT_LT(below.max_rest_error, 1e-4);
  const PullResult above = pullAndRelease(0.5 * probe.max_shear, 0.006, 0);
  EXPECT_GT(above.splits, 0);
}

TEST(Tearing, BreaksWhereEq6SaysAndPlacesParticleBetweenWithinRange) {
  TearSheet<double> s = makeTearGrid<double>(7, 7, kH, kRhoA, Vec3d(0, 0, 0), kK, 1.0);
  // Lift the centre particle out of plane: its neighbours' bonds stretch, each differently.
  s.x[24] += Vec3d(0.0, 0.0, 0.5 * kH);
  const double tau = 0.5 * maxShear(s);
  std::fill(s.tau_f.begin(), s.tau_f.end(), tau);
  const TearSheet<double> before = s;
  TearParams<double> p;
  p.seed = 11;
  TearCandidates<double> c;
  const TearStepStats st = cpu::tearStepCpu(s, p, &c);
  ASSERT_GT(st.splits, 0);
  int checked = 0;
  std::int32_t next_new = std::int32_t(before.size());
  for (std::size_t i = 0; i < before.size(); ++i) {
    std::int32_t j = -1;
    const bool eq6 = maxShearOf(before, i, &j) >= tau;
    if (c.yield[i]) {
      EXPECT_TRUE(eq6) << "particle " << i;
    }
    if (!c.accept[i]) continue;
    ASSERT_TRUE(eq6);
    EXPECT_EQ(c.partner[i], j) << "the broken bond is the particle's most strained bond";
    const std::int32_t nn = next_new++;  // new particles are numbered in the order of their parents
    // Bond (i, j) is gone, (new, j) exists.
    auto bonded = [&](std::int32_t a, std::int32_t b) {
      for (std::int32_t q = s.pe_offsets[a]; q < s.pe_offsets[a + 1]; ++q)
        if (s.pe_partner[q] == b) return true;
      return false;
    };
    EXPECT_FALSE(bonded(std::int32_t(i), j));
    EXPECT_TRUE(bonded(nn, j));
    // New particle on the segment i -> j at t within [0.9, 1.1] t_pred (clamped to [0.05, 0.95]).
    const Vec3d seg = before.x[j] - before.x[i];
    const double t = dot(s.x[nn] - before.x[i], seg) / norm2(seg);
    EXPECT_NEAR(norm(cross(s.x[nn] - before.x[i], seg)), 0.0, 1e-12);
    const double tp = c.t_pred[i];
    EXPECT_GE(t, std::max(0.05, 0.9 * tp) - 1e-12);
    EXPECT_LE(t, std::min(0.95, 1.1 * tp) + 1e-12);
    ++checked;
  }
  EXPECT_EQ(checked, st.splits);
  expectValid(s);
}

// A sheet loaded biaxially, x = diag(a, b, 1) X, with unequal principal stretches of either sign: the principal-stress
// criterion yields exactly where the analytic plane-stress Tresca shear (the out-of-plane principal stress 0
// included) reaches tau_f. Every interior particle gets tau_f 1 % below its own shear (even index: must yield) or
// 1 % above it (odd: must not). In tension-tension the out-of-plane 0 is s_3 and the shear is s_1 / 2, far from the
// in-plane difference (s_1 - s_2) / 2 that omitting it would give. In compression-compression the 0 is s_1, whose
// direction is the sheet normal: that split plane is the sheet itself and separates no triangles, so nothing yields
// even past tau_f (detectYield counts only splits that separate triangles; a compressed membrane does not tear).
TEST(Tearing, PrincipalCriterionYieldsAtThePlaneStressTrescaShearUnderBiaxialLoad) {
  struct Load {
    const char* what;
    double a, b;
    bool can_split;
  };
  for (const Load& load : {Load{"tension-tension", 1.10, 1.04, true}, Load{"tension-compression", 1.08, 0.95, true},
                           Load{"compression-compression", 0.92, 0.97, false}}) {
    // Even nx: the index parity alternates along x only, so both outcomes fall on 4-bond and on 8-bond particles
    // alike (the grid's diagonals alternate).
    const int nx = 8, ny = 6;
    TearSheet<double> s = makeTearGrid<double>(nx, ny, kH, kRhoA, Vec3d(0, 0, 0), kK, 1.0);
    for (std::size_t i = 0; i < s.size(); ++i) s.x[i] = Vec3d(load.a * s.rest[i].x, load.b * s.rest[i].y, 0.0);
    std::vector<char> interior(s.size(), 0);
    std::vector<double> tau(s.size(), 0.0);
    for (int j = 1; j + 1 < ny; ++j)
      for (int i = 1; i + 1 < nx; ++i) {
        const std::size_t id = std::size_t(j * nx + i);
        interior[id] = 1;
        tau[id] = planeStressTresca(s, id);
        s.tau_f[id] = tau[id] * (id % 2 == 0 ? 0.99 : 1.01);
      }
    TearParams<double> p;
    p.criterion = TearCriterion::TrescaPrincipal;
    TearCandidates<double> c;
    cpu::tearStepCpu(s, p, &c);
    int past = 0, below = 0;
    for (std::size_t i = 0; i < interior.size(); ++i) {
      if (!interior[i]) continue;
      ASSERT_GT(tau[i], 0.0);
      const bool past_tau = i % 2 == 0;
      EXPECT_EQ(bool(c.yield[i]), load.can_split && past_tau)
          << load.what << ", particle " << i << ": Tresca shear " << tau[i] << " Pa, tau_f " << s.tau_f[i] << " Pa";
      (past_tau ? past : below) += 1;
    }
    EXPECT_GT(past, 5) << load.what;
    EXPECT_GT(below, 5) << load.what;
  }
  // The load cases do tell the plane-stress shear from the in-plane one (4-bond particles: sigma = diag(k (a - 1),
  // k (b - 1)) / 2 exactly): tension-tension k 0.05 / 2 against k 0.03 / 2.
  const int nx = 8, ny = 6;
  TearSheet<double> s = makeTearGrid<double>(nx, ny, kH, kRhoA, Vec3d(0, 0, 0), kK, 1.0);
  for (std::size_t i = 0; i < s.size(); ++i) s.x[i] = Vec3d(1.10 * s.rest[i].x, 1.04 * s.rest[i].y, 0.0);
  int four_bond = 0;
  for (int j = 1; j + 1 < ny; ++j)
    for (int i = 1; i + 1 < nx; ++i) {
      const std::size_t id = std::size_t(j * nx + i);
      if (s.pe_offsets[id + 1] - s.pe_offsets[id] != 4) continue;
      ++four_bond;
      EXPECT_NEAR(planeStressTresca(s, id), kK * 0.05 / 2, 1e-9 * kK) << "particle " << id;
    }
  EXPECT_GT(four_bond, 5);
}

TEST(Tearing, MassAndMomentumConservedInBreakingStep) {
  for (TearCriterion crit : {TearCriterion::Threshold, TearCriterion::TrescaBonds, TearCriterion::TrescaPrincipal}) {
    TearSheet<double> s = makeTearGrid<double>(20, 20, kH, kRhoA, Vec3d(0, 0, 0), kK, 1.0);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    for (std::size_t i = 0; i < s.size(); ++i) {
      s.x[i] += Vec3d(u(rng), u(rng), u(rng)) * (0.15 * kH);
      s.v[i] = Vec3d(u(rng), u(rng), u(rng));
    }
    const double tau = 0.1 * maxShear(s);
    std::fill(s.tau_f.begin(), s.tau_f.end(), tau);
    TearParams<double> p;
    p.criterion = crit;
    p.break_strain = 0.05;
    const double m0 = totalMass(s);
    const Vec3d p0 = totalMomentum(s);
    const TearStepStats st = cpu::tearStepCpu(s, p);
    EXPECT_GT(st.splits, 5) << tearCriterionName(crit);
    EXPECT_TRUE(test::relNear(totalMass(s), m0, 1e-14)) << tearCriterionName(crit);
    EXPECT_NEAR(norm(totalMomentum(s) - p0), 0.0, 1e-14);
    for (double m : s.mass) EXPECT_GT(m, 0.0);
  }
}

namespace {
// Repeatedly jiggles and tears a sheet; returns total splits; checks validity every step.
int tearManyTimes(TearSheet<double>& s, const TearParams<double>& p, int steps, std::uint32_t jiggle_seed) {
  std::mt19937 rng(jiggle_seed);
  std::uniform_real_distribution<double> u(-1, 1);
  int splits = 0;
  for (int k = 0; k < steps; ++k) {
    for (std::size_t i = 0; i < s.size(); ++i) s.x[i] = s.rest[i] + Vec3d(u(rng), u(rng), u(rng)) * (0.12 * kH);
    splits += cpu::tearStepCpu(s, p).splits;
    const TearMeshCheck c = checkTearMesh(s);
    if (!c.valid()) {
      ADD_FAILURE() << "invalid mesh after step " << k << ": dead " << c.dead_refs << " degenerate " << c.degenerate
                    << " inverted " << c.inverted << " duplicates " << c.duplicates << " non-manifold "
                    << c.non_manifold_edges << " inconsistent " << c.inconsistent_edges;
      break;
    }
  }
  return splits;
}
}  // namespace

TEST(Tearing, MeshStaysValidAfterThousandsOfBreaks) {
  for (TearCriterion crit : {TearCriterion::TrescaBonds, TearCriterion::Threshold, TearCriterion::TrescaPrincipal}) {
    TearSheet<double> s = makeTearGrid<double>(40, 40, kH, kRhoA, Vec3d(0, 0, 0), kK, 120.0);
    TearParams<double> p;
    p.criterion = crit;
    p.break_strain = 0.12;
    const double m0 = totalMass(s);
    const int splits = tearManyTimes(s, p, 12, 9);
    EXPECT_GT(splits, 2000) << tearCriterionName(crit);
    EXPECT_TRUE(test::relNear(totalMass(s), m0, 1e-12)) << tearCriterionName(crit);
    expectValid(s);
  }
}

TEST(Tearing, SameSeedSameDebrisDifferentSeedDifferentDebris) {
  auto run = [](std::uint32_t seed) {
    TearSheet<double> s = makeTearGrid<double>(24, 24, kH, kRhoA, Vec3d(0, 0, 0), kK, 120.0);
    TearParams<double> p;
    p.seed = seed;
    tearManyTimes(s, p, 4, 2);
    return s;
  };
  const TearSheet<double> a = run(5), b = run(5), c = run(6);
  ASSERT_GT(a.size(), 24u * 24u);
  EXPECT_EQ(a.tris, b.tris);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(norm(a.rest[i] - b.rest[i]), 0.0);
  bool differs = a.size() != c.size();
  for (std::size_t i = 0; i < std::min(a.size(), c.size()) && !differs; ++i) differs = norm(a.rest[i] - c.rest[i]) > 0;
  EXPECT_TRUE(differs);
}

namespace {
double restAreaOf(const TearSheet<double>& s) {
  double a = 0;
  for (const auto& t : s.tris) a += 0.5 * norm(cross(s.rest[t[1]] - s.rest[t[0]], s.rest[t[2]] - s.rest[t[0]]));
  return a;
}
}  // namespace

TEST(Tearing, SameResultForAnyThreadCount) {
  auto run = [](int threads) {
    const int old = omp_get_max_threads();
    omp_set_num_threads(threads);
    TearSheet<double> s = makeTearGrid<double>(30, 30, kH, kRhoA, Vec3d(0, 0, 0), kK, 120.0);
    TearParams<double> p;
    p.criterion = TearCriterion::TrescaPrincipal;
    tearManyTimes(s, p, 3, 8);
    omp_set_num_threads(old);
    return s;
  };
  const TearSheet<double> a = run(1), b = run(3);
  EXPECT_EQ(a.tris, b.tris);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(norm(a.x[i] - b.x[i]), 0.0);
    EXPECT_EQ(a.mass[i], b.mass[i]);
  }
}

TEST(Tearing, DebrisBoundaryRougherThanTraditional) {
  // The paper's Fig. 5 cases: remove a rectangle and a vertical strip from a sheet clamped on its border.
  // Traditional: the particles are deleted. Tresca: they are gripped and lifted 5 cm out of the sheet while
  // eq. 6 tears the tissue around them, then deleted. The hole's boundary (rest configuration) is measured by
  // its length L and the scale-free roughness L^2 / A (A the hole's area; 16 for a clean square).
  for (int shape = 0; shape < 2; ++shape) {
    double len[2], rough[2];
    int splits = 0;
    for (int tresca = 0; tresca < 2; ++tresca) {
      TearSheet<double> s = makeTearGrid<double>(22, 22, kH, kRhoA, Vec3d(0, 0, 0), kK, 400.0);
      fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1e-3, 1, 1));
      fixTearParticles(s, Vec3d(0.209, -1, -1), Vec3d(1, 1, 1));
      fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1, 1e-3, 1));
      fixTearParticles(s, Vec3d(-1, 0.209, -1), Vec3d(1, 1, 1));
      const double outer = tearBoundaryLength(s, true), area0 = restAreaOf(s);
      const auto mark = shape == 0 ? markInBox(s, Vec3d(0.065, 0.075, -1), Vec3d(0.145, 0.135, 1))
                                   : markNearSegment(s, Vec3d(0.105, 0.05, 0), Vec3d(0.105, 0.16, 0), 0.006);
      TearParams<double> p;
      p.criterion = tresca ? TearCriterion::TrescaBonds : TearCriterion::Threshold;
      p.break_strain = 0.08;
      TearingDriver<double> d(s, p, softSkin(), quietStep(), BackendKind::Cpu);
      int removed = 0;
      if (tresca)
        splits = d.tearOut(mark, Vec3d(0, 0, 0.05), 10, &removed);
      else
        removed = d.removeParticles(mark);
      EXPECT_GT(removed, 0);
      expectValid(d.sheet());
      len[tresca] = tearBoundaryLength(d.sheet(), true) - outer;
      const double hole = area0 - restAreaOf(d.sheet());
      ASSERT_GT(hole, 0.0);
      rough[tresca] = len[tresca] * len[tresca] / hole;
    }
    EXPECT_GT(splits, 0);
    EXPECT_GT(len[0], 0.0);
    EXPECT_GT(rough[1], 1.2 * rough[0]) << "shape " << shape << ": traditional L " << len[0] << " m, L^2/A " << rough[0]
                                        << "; tresca L " << len[1] << " m, L^2/A " << rough[1];
    std::printf("removal shape %d: traditional L %.3f m, L^2/A %.1f; tresca L %.3f m, L^2/A %.1f (%d splits)\n", shape,
                len[0], rough[0], len[1], rough[1], splits);
  }
}

TEST(Tearing, DebrisFringeRemovalKeepsValidMesh) {
  TearSheet<double> s = makeTearGrid<double>(30, 30, kH, kRhoA, Vec3d(0, 0, 0), kK, 100.0);
  const std::size_t tris0 = s.tris.size();
  TearParams<double> p;
  const int removed = removeTearParticles(s, markInBox(s, Vec3d(0.095, 0.105, -1), Vec3d(0.195, 0.175, 1)), true, p);
  EXPECT_GT(removed, 0);
  EXPECT_LT(s.tris.size(), tris0);
  expectValid(s);
}

TEST(Tearing, PullTearOpensCrackInWeakBand) {
  // A strip pulled apart across a weak band (tau_f = 150 Pa at x in [0.085, 0.115], 1e9 Pa elsewhere). The
  // Tresca criteria (bond extrema and principal stresses) split only particles of the band, as eq. 6 says;
  // the traditional criterion (one global break strain) tears wherever the strain passes it.
  double extra[3];
  int splits[3];
  const TearCriterion crits[3] = {TearCriterion::Threshold, TearCriterion::TrescaBonds, TearCriterion::TrescaPrincipal};
  for (int c = 0; c < 3; ++c) {
    TearSheet<double> s = makeTearGrid<double>(21, 10, kH, kRhoA, Vec3d(0, 0, 0), kK, 1e9);
    // The principal variant's virial shear is about half the bond-extrema shear (docs/tearing.md).
    const double tau = crits[c] == TearCriterion::TrescaPrincipal ? 75.0 : 150.0;
    applyTearRegions(s, {TearRegion{Vec3d(0.085, -1, -1), Vec3d(0.115, 1, 1), kK, tau}});
    fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1e-3, 1, 1));
    const double outer = tearBoundaryLength(s, true);
    const std::size_t n0 = s.size();
    std::vector<std::int32_t> grasp;
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s.rest[i].x > 0.199) grasp.push_back(std::int32_t(i));
    TearParams<double> p;
    p.criterion = crits[c];
    p.break_strain = 0.03;  // the same stress scale: k * strain = 300 Pa = 2 tau_f
    TearingDriver<double> d(s, p, softSkin(), quietStep(), BackendKind::Cpu);
    splits[c] = 0;
    for (int f = 0; f < 15; ++f) {
      std::vector<Vec3d> to;
      for (std::int32_t id : grasp) to.push_back(d.sheet().rest[id] + Vec3d(0.008 * (f + 1), 0, 0));
      splits[c] += d.advance(grasp, to).splits;
    }
    expectValid(d.sheet());
    extra[c] = tearBoundaryLength(d.sheet(), true) - outer;
    EXPECT_GT(splits[c], 5) << tearCriterionName(crits[c]);
    EXPECT_GT(extra[c], 0.0) << tearCriterionName(crits[c]);
    if (crits[c] != TearCriterion::Threshold)
      for (std::size_t i = n0; i < d.sheet().size(); ++i) {
        // A new particle lies between a band particle (x in [0.09, 0.11]) and a partner one spacing away.
        EXPECT_GE(d.sheet().rest[i].x, 0.08 - 1e-9) << tearCriterionName(crits[c]) << " particle " << i;
        EXPECT_LE(d.sheet().rest[i].x, 0.12 + 1e-9) << tearCriterionName(crits[c]) << " particle " << i;
      }
  }
  std::printf("pull tear: traditional %.4f m boundary / %d splits, tresca %.4f m / %d, principal %.4f m / %d\n",
              extra[0], splits[0], extra[1], splits[1], extra[2], splits[2]);
}

TEST(Tearing, JacobiModelWithoutColoringMatchesFinalize) {
  TearSheet<double> s = makeTearGrid<double>(9, 7, kH, kRhoA, Vec3d(0, 0, 0), kK, 100.0);
  fixTearParticles(s, Vec3d(-1, -1, -1), Vec3d(1e-3, 1, 1));
  TearModelOptions a = softSkin(), b = softSkin();
  b.coloring = false;
  const PbdModel<double> ma = buildTearPbdModel(s, a), mb = buildTearPbdModel(s, b);
  ASSERT_EQ(ma.blocks.size(), 2u);
  ASSERT_EQ(mb.blocks.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(ma.blocks[k].ids, mb.blocks[k].ids);
    EXPECT_EQ(ma.blocks[k].particle_offsets, mb.blocks[k].particle_offsets);
    EXPECT_EQ(ma.blocks[k].particle_slots, mb.blocks[k].particle_slots);
    EXPECT_EQ(ma.blocks[k].jacobi_scale, mb.blocks[k].jacobi_scale);
    EXPECT_GT(ma.blocks[k].coloring.colorCount(), 0);
    EXPECT_EQ(mb.blocks[k].coloring.colorCount(), 0);
  }
  EXPECT_EQ(ma.inv_mass, mb.inv_mass);
}

TEST(Tearing, BadInputIsRefused) {
  EXPECT_THROW(makeTearGrid<double>(1, 5, kH, kRhoA, Vec3d(), kK, 1.0), InputError);
  EXPECT_THROW(makeTearGrid<double>(5, 5, kH, kRhoA, Vec3d(), kK, -1.0), InputError);
  EXPECT_THROW(parseTearCriterion("von_mises", "scene.json", "tearing.criterion"), InputError);
  TearSheet<double> s = makeTearGrid<double>(5, 5, kH, kRhoA, Vec3d(), kK, 1.0);
  TearParams<double> p;
  p.t_lo = 0.0;
  EXPECT_THROW(TearingDriver<double>(s, p, softSkin(), quietStep(), BackendKind::Cpu), InputError);
  EXPECT_THROW(removeTearParticles(s, std::vector<std::uint8_t>(3, 0), true, TearParams<double>()), InputError);
}

// The bending block comes from merging the particle -> triangle lists; after thousands of splits and a tissue
// removal it must equal the straightforward reference: every edge key with exactly two (key, opposite vertex)
// half-edges, in key order, wings ascending, rest angle from the rest positions (exact: same arithmetic).
TEST(Tearing, BendingBlockAfterSplitsMatchesHalfEdgeReference) {
  TearSheet<double> s = makeTearGrid<double>(30, 30, kH, kRhoA, Vec3d(0, 0, 0), kK, 120.0);
  TearParams<double> p;
  p.break_strain = 0.12;
  EXPECT_GT(tearManyTimes(s, p, 8, 5), 200);
  std::vector<std::uint8_t> mark(s.size(), 0);
  for (std::size_t i = 0; i < s.size(); ++i) mark[i] = s.rest[i].x < 0.05 && s.rest[i].y < 0.05;
  removeTearParticles(s, mark, true, p);
  s.rebuildTopology();
  const PbdModel<double> m = buildTearPbdModel(s, softSkin());
  ASSERT_EQ(m.blocks.size(), 2u);
  const PbdConstraintBlock<double>& bend = m.blocks[1];
  std::vector<std::pair<std::uint64_t, std::int32_t>> half;
  for (const auto& t : s.tris)
    for (int c = 0; c < 3; ++c) {
      std::int32_t a = t[c], b = t[(c + 1) % 3];
      if (a > b) std::swap(a, b);
      half.push_back({(std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b), t[(c + 2) % 3]});
    }
  std::sort(half.begin(), half.end());
  std::vector<std::int32_t> ids;
  std::vector<double> rest;
  for (std::size_t h = 0; h < half.size();) {
    std::size_t e = h;
    while (e < half.size() && half[e].first == half[h].first) ++e;
    if (e - h == 2) {
      const std::int32_t a = std::int32_t(half[h].first >> 32), b = std::int32_t(half[h].first & 0xffffffffu);
      for (std::int32_t q : {a, b, half[h].second, half[h + 1].second}) ids.push_back(q);
      rest.push_back(pbd::dihedralAngle(s.rest[a], s.rest[b], s.rest[half[h].second], s.rest[half[h + 1].second]));
    }
    h = e;
  }
  EXPECT_EQ(bend.ids, ids);
  EXPECT_EQ(bend.rest, rest);
  ASSERT_EQ(bend.offsets.size(), rest.size() + 1);
  for (std::size_t c = 0; c <= rest.size(); ++c) EXPECT_EQ(bend.offsets[c], std::int32_t(4 * c));
  // A stale adjacency is refused rather than read out of bounds.
  TearSheet<double> stale = s;
  stale.pt_offsets.clear();
  EXPECT_THROW(buildTearPbdModel(stale, softSkin()), InputError);
}

// rebuildTopology builds the bonds per particle (no global sort): after splits and a removal it must equal the
// sorted unique mesh edges, and the CSR lists must hold exactly each particle's partners and triangles, ascending.
TEST(Tearing, RebuiltAdjacencyMatchesSortedEdgeReference) {
  TearSheet<double> s = makeTearGrid<double>(25, 20, kH, kRhoA, Vec3d(0, 0, 0), kK, 120.0);
  TearParams<double> p;
  p.criterion = TearCriterion::Threshold;
  p.break_strain = 0.12;
  EXPECT_GT(tearManyTimes(s, p, 6, 3), 100);
  std::vector<std::uint8_t> mark(s.size(), 0);
  for (std::size_t i = 0; i < s.size(); ++i) mark[i] = s.rest[i].x > 0.15 && s.rest[i].y > 0.1;
  removeTearParticles(s, mark, false, p);
  s.rebuildTopology();
  std::vector<std::pair<std::int32_t, std::int32_t>> ref;
  std::vector<std::vector<std::int32_t>> partners(s.size()), tris_of(s.size());
  for (std::size_t t = 0; t < s.tris.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const std::int32_t a = s.tris[t][c], b = s.tris[t][(c + 1) % 3];
      ref.push_back({std::min(a, b), std::max(a, b)});
      tris_of[a].push_back(std::int32_t(t));
    }
  std::sort(ref.begin(), ref.end());
  ref.erase(std::unique(ref.begin(), ref.end()), ref.end());
  ASSERT_EQ(s.edge_a.size(), ref.size());
  for (std::size_t e = 0; e < ref.size(); ++e) {
    EXPECT_EQ(s.edge_a[e], ref[e].first) << e;
    EXPECT_EQ(s.edge_b[e], ref[e].second) << e;
    partners[ref[e].first].push_back(ref[e].second);
    partners[ref[e].second].push_back(ref[e].first);
  }
  ASSERT_EQ(s.pe_offsets.size(), s.size() + 1);
  ASSERT_EQ(s.pt_offsets.size(), s.size() + 1);
  for (std::size_t i = 0; i < s.size(); ++i) {
    std::sort(partners[i].begin(), partners[i].end());
    EXPECT_EQ(
        std::vector<std::int32_t>(s.pe_partner.begin() + s.pe_offsets[i], s.pe_partner.begin() + s.pe_offsets[i + 1]),
        partners[i])
        << i;
    EXPECT_EQ(std::vector<std::int32_t>(s.pt_tris.begin() + s.pt_offsets[i], s.pt_tris.begin() + s.pt_offsets[i + 1]),
              tris_of[i])
        << i;
  }
}
