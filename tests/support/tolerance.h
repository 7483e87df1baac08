// Tolerance checks shared by the tests: relative error (with an absolute floor) and the figures in the failure.
#pragma once

#include <gtest/gtest.h>

#include <cmath>

namespace inc::test {

// |actual - expected| <= rel |expected| + abs: the check the tests spelled EXPECT_NEAR(a, b, rel * b), whose
// failure gives only absolute figures. This one also says the relative error against the relative bound, so a
// figure that drifted by 2.1 % against a 2 % bound reads as such. EXPECT_TRUE(test::relNear(a, b, 0.02)) << "what".
inline ::testing::AssertionResult relNear(double actual, double expected, double rel, double abs = 0.0) {
  const double err = std::fabs(actual - expected), bound = rel * std::fabs(expected) + abs;
  if (err <= bound) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << actual << ", expected " << expected << ": error " << err << " ("
                                       << 100 * err / std::fabs(expected) << " % of expected) > bound " << bound << " ("
                                       << 100 * rel << " % + " << abs << ")";
}

}  // namespace inc::test
