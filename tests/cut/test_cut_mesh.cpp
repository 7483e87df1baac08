// Cut-surface reconstruction: planar splits give closed, manifold, outward pieces with the analytic volumes.
#include <gtest/gtest.h>

#include <cmath>

#include "host/assembly/organ_shapes.h"
#include "host/cut/cut_mesh.h"
#include "model/input_error.h"
#include "tests/support/cut_fixtures.h"

namespace inc {
namespace {

void expectWatertightPiece(const TriangleMesh& m, const char* what) {
  const MeshReport r = analyzeMesh(m);
  EXPECT_TRUE(r.closed()) << what << ": boundary " << r.boundary_edges << " non-manifold " << r.non_manifold_edges;
  EXPECT_EQ(r.inconsistent_edges, 0) << what;
  EXPECT_EQ(r.degenerate_triangles, 0) << what;
  EXPECT_GT(r.signed_volume, 0.0) << what;  // outward oriented
}

TEST(CutMesh, StraightCutThroughABoxGivesTheAnalyticVolumes) {
  const Vec3d half(0.05, 0.03, 0.02);
  const TriangleMesh box = makeBoxMesh(half, 6);
  const double x0 = 0.0137;  // not on a grid line of the box mesh
  const CutMeshResult r = splitMeshByPlane(box, Vec3d(x0, 0, 0), Vec3d(1, 0, 0));
  expectWatertightPiece(r.positive, "x > x0 piece");
  expectWatertightPiece(r.negative, "x < x0 piece");
  EXPECT_EQ(analyzeMesh(r.positive).components, 1);
  EXPECT_EQ(analyzeMesh(r.negative).components, 1);
  EXPECT_EQ(r.contour_loops, 1);
  EXPECT_EQ(r.forced_ears, 0);
  const double area = 4.0 * half.y * half.z;
  // Planar faces split by a plane: exact up to rounding, tolerance 1e-9 relative.
  EXPECT_NEAR(analyzeMesh(r.positive).signed_volume, (half.x - x0) * area, 1e-9 * area * half.x);
  EXPECT_NEAR(analyzeMesh(r.negative).signed_volume, (half.x + x0) * area, 1e-9 * area * half.x);
  for (const auto& v : r.positive.vertices) EXPECT_GE(v.x, x0 - 1e-12);
  for (const auto& v : r.negative.vertices) EXPECT_LE(v.x, x0 + 1e-12);
  // The merged surface (what the viewer draws) is closed with two components.
  const MeshReport both = analyzeMesh(mergeMeshes(r.positive, r.negative));
  EXPECT_TRUE(both.closed());
  EXPECT_EQ(both.components, 2);
}

TEST(CutMesh, SweptSurfacePlaneDrivesTheSplit) {
  const SweptSurface s = cuttest::straightSweep(-0.2, 0.2, -0.2, 0.2);  // z = 0, normal +z
  Vec3d p, n;
  ASSERT_TRUE(planeOfSweptSurface(s, p, n, 1e-9));
  EXPECT_NEAR(n.z, 1.0, 1e-12);
  const TriangleMesh box = makeBoxMesh(Vec3d(0.05, 0.03, 0.02), 5);  // z grid lines at +-0.004: none at 0
  const CutMeshResult r = splitMeshByPlane(box, p, n);
  expectWatertightPiece(r.positive, "top");
  expectWatertightPiece(r.negative, "bottom");
  const double half_volume = 0.1 * 0.06 * 0.02;
  EXPECT_NEAR(analyzeMesh(r.positive).signed_volume, half_volume, 1e-9 * half_volume);
  // A curved sweep is not planar: refused rather than cut wrongly.
  std::vector<BladePose> poses;
  for (int k = 0; k < 5; ++k)
    poses.push_back({Vec3d(0.02 * k, -0.1, 0.01 * k * k), Vec3d(0.02 * k, 0.1, 0.01 * k * k)});
  EXPECT_FALSE(planeOfSweptSurface(sweepSurface(poses), p, n, 1e-4));
}

TEST(CutMesh, SeveralSuccessiveCutsOfTheLiverStayClosedAndKeepTheVolume) {
  LiverLikeOptions o;
  o.target_vertices = 1500;
  const TriangleMesh liver = makeLiverLikeMesh(o);
  const double v0 = analyzeMesh(liver).signed_volume;
  std::vector<TriangleMesh> pieces{liver};
  const Vec3d normals[3] = {Vec3d(1, 0.2, 0.1), Vec3d(0.1, 1, -0.3), Vec3d(0.3, -0.2, 1)};
  const Vec3d points[3] = {Vec3d(0.011, 0.003, 0.001), Vec3d(-0.004, 0.006, 0.002), Vec3d(0.002, -0.001, 0.003)};
  for (int c = 0; c < 3; ++c) {
    std::vector<TriangleMesh> next;
    for (const auto& piece : pieces) {
      const CutMeshResult r = splitMeshByPlane(piece, points[c], normals[c]);
      for (const TriangleMesh* m : {&r.positive, &r.negative})
        if (!m->triangles.empty()) {
          expectWatertightPiece(*m, "liver piece");
          next.push_back(*m);
        }
    }
    pieces = next;
    double v = 0.0;
    for (const auto& piece : pieces) v += analyzeMesh(piece).signed_volume;
    EXPECT_NEAR(v / v0, 1.0, 1e-9) << "after cut " << c + 1;
  }
  EXPECT_GE(pieces.size(), 6u);
}

TEST(CutMesh, DeterministicAndBadPlaneIsAnInputError) {
  const TriangleMesh box = makeBoxMesh(Vec3d(0.05, 0.03, 0.02), 4);
  const CutMeshResult a = splitMeshByPlane(box, Vec3d(0.001, 0.002, 0.0), Vec3d(1, 1, 0.5));
  const CutMeshResult b = splitMeshByPlane(box, Vec3d(0.001, 0.002, 0.0), Vec3d(1, 1, 0.5));
  ASSERT_EQ(a.positive.triangles, b.positive.triangles);
  ASSERT_EQ(a.positive.vertices.size(), b.positive.vertices.size());
  for (std::size_t i = 0; i < a.positive.vertices.size(); ++i)
    ASSERT_EQ(norm(a.positive.vertices[i] - b.positive.vertices[i]), 0.0);
  expectWatertightPiece(a.positive, "tilted +");
  expectWatertightPiece(a.negative, "tilted -");
  EXPECT_THROW(splitMeshByPlane(box, Vec3d(0, 0, 0), Vec3d(0, 0, 0)), InputError);
}

}  // namespace
}  // namespace inc
