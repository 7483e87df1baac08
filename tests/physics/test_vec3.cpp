// Tests for the shared 3-vector / 3x3 matrix math used by both backends.
#include <gtest/gtest.h>

#include "physics/vec3.h"

using namespace inc;

TEST(Vec3Math, DeterminantAndAdjugateGiveInverse) {
  Mat3d a = Mat3d::fromRows({2, 1, 0}, {1, 3, 1}, {0, 1, 4});
  const double d = det(a);
  EXPECT_NEAR(d, 2 * (12 - 1) - 1 * (4 - 0), 1e-14);  // cofactor expansion by hand = 18
  Mat3d inv = adjugate(a) * (1.0 / d);
  Mat3d id = a * inv;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(id(r, c), r == c ? 1.0 : 0.0, 1e-14);
}

TEST(Vec3Math, CrossIsOrthogonalAndRightHanded) {
  Vec3d x{1, 0, 0}, y{0, 1, 0};
  Vec3d z = cross(x, y);
  EXPECT_DOUBLE_EQ(z.z, 1.0);
  EXPECT_DOUBLE_EQ(dot(z, x), 0.0);
  EXPECT_DOUBLE_EQ(norm(Vec3d{3, 4, 12}), 13.0);
}

TEST(Vec3Math, OuterTraceAndFrobenius) {
  Vec3d a{1, 2, 3}, b{4, 5, 6};
  EXPECT_DOUBLE_EQ(trace(outer(a, b)), dot(a, b));
  EXPECT_DOUBLE_EQ(ddot(Mat3d::identity(), Mat3d::identity()), 3.0);
  EXPECT_TRUE(isFinite(a));
  EXPECT_FALSE(isFinite(Vec3d{1, std::nan(""), 0}));
}
