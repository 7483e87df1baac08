// Tests of the speed/accuracy sweep: the Euler-Bernoulli reference, the Pareto front, a quick sweep of MLS and PBD.
#include <gtest/gtest.h>

#include <cmath>

#include "host/embedded_scenes.h"
#include "host/input_error.h"
#include "host/scene_loader.h"
#include "host/tradeoff.h"

using namespace inc;

namespace {

Scene smallBeam() {
  Scene s = parseScene(findEmbeddedScene("beam")->json, "<embedded:beam>", ".");
  s.geometry.size = {0.04, 0.016, 0.016};
  s.geometry.center = {0.02, 0, 0};
  s.geometry.spacing = 0.004;
  s.fixed = {FixedRegion{{-0.001, -0.009, -0.009}, {0.0041, 0.009, 0.009}}};
  return s;
}

}  // namespace

TEST(Tradeoff, EulerBernoulliTipDeflectionFormula) {
  // q L^4 / (8 E I) with q = rho g b h, I = b h^3 / 12 = 1.5 rho g L^4 / (E h^2) for any b: hand value
  // 1.5 * 1000 * 9.81 * 0.1^4 / (1e6 * 0.02^2) = 3.67875e-3 m. Tolerance: rounding only (1e-12 relative).
  const double w = eulerBernoulliTipDeflection(0.1, 0.03, 0.02, 1.0e6, 1000.0, 9.81);
  EXPECT_NEAR(w, 3.67875e-3, 1e-12 * 3.67875e-3);
}

TEST(Tradeoff, ParetoFrontKeepsOnlyUndominatedSettingsWithinTheBudget) {
  auto r = [](double ms, double err, bool finite = true) {
    TradeoffRow x;
    x.ms_per_frame = ms;
    x.error = err;
    x.finite = finite;
    return x;
  };
  const std::vector<TradeoffRow> rows = {r(0.5, 0.4), r(0.8, 0.5), r(0.9, 0.1), r(3.0, 0.01), r(0.2, 0.0, false),
                                         r(12.0, 0.001), r(20.0, 0.0)};
  EXPECT_EQ(paretoFront(rows, 1.0), (std::vector<std::size_t>{0, 2}));  // 0.8/0.5 is dominated; NaN run excluded
  EXPECT_EQ(paretoFront(rows, 16.0), (std::vector<std::size_t>{0, 2, 3, 5}));
  EXPECT_TRUE(paretoFront(rows, 0.1).empty());
}

TEST(Tradeoff, QuickSweepOfACantileverMeasuresMlsAgainstEulerBernoulliAndPbdAgainstAReference) {
  Scene s = smallBeam();
  s.models.pbd_metaballs = true;
  TradeoffOptions o;
  o.quick = true;
  const TradeoffResult r = runTradeoff(s, o);
  ASSERT_EQ(r.references.size(), 2u);
  EXPECT_NE(r.references[0].find("Euler-Bernoulli"), std::string::npos);
  EXPECT_NE(r.references[1].find("float64 run at the finest setting"), std::string::npos);
  int mls = 0, pbd = 0;
  for (const TradeoffRow& x : r.rows) {
    // A setting the model refuses (e.g. a PBD substep too long for the lattice) is kept as a row that names
    // the refused key, and is never a Pareto candidate.
    if (x.note.find("refused") != std::string::npos) {
      EXPECT_NE(x.note.find("solver."), std::string::npos) << x.note;
      EXPECT_FALSE(x.finite);
      continue;
    }
    (x.model == "mls" ? mls : pbd)++;
    EXPECT_TRUE(x.finite) << x.model << " " << x.knob << " " << x.note;
    EXPECT_GT(x.ms_per_frame, 0.0);
    EXPECT_GT(x.particles, 0u);
    EXPECT_TRUE(std::isfinite(x.error));
    // The beam sags under gravity: the measured tip moves down (4 frames, not yet settled).
    EXPECT_GT(x.observable, 0.0) << x.model << " " << x.knob;
  }
  EXPECT_GE(mls, 4);  // baseline, spacing, support, safety, precision
  EXPECT_GE(pbd, 4);  // baseline, iterations, substeps, spheres, precision
  const std::string md = tradeoffMarkdown(r, o.budgets_ms);
  EXPECT_NE(md.find("Pareto-optimal settings within 16 ms"), std::string::npos);
  EXPECT_NE(tradeoffCsv(r).find("model,knob,value"), std::string::npos);
}

TEST(Tradeoff, BadInputIsRefusedNamingTheKey) {
  Scene s = smallBeam();
  s.models.mls = false;
  try {
    runTradeoff(s, TradeoffOptions{});
    FAIL() << "a scene without MLS or PBD must be refused";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "models");
  }
  EXPECT_THROW(parseBudgets("1,abc"), InputError);
  EXPECT_THROW(parseBudgets("-3"), InputError);
  EXPECT_EQ(parseBudgets("1,16"), (std::vector<double>{1.0, 16.0}));
}
