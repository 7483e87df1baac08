// The stability matrix on the CPU: extreme materials, steps, spacings, compression, isolated particles, jitter, soak.
#include "tests/support/stability_matrix.h"

using namespace inc;
using namespace inc::stability;

TEST(StabilityMatrix, MlsExtremeMaterials) { materialsCase(BackendKind::Cpu, true); }
TEST(StabilityMatrix, PbdExtremeMaterials) { materialsCase(BackendKind::Cpu, false); }
TEST(StabilityMatrix, MlsTimeStepUpToTwiceTheLimitIsStableOrRefused) { mlsTimeStepCase(BackendKind::Cpu); }
TEST(StabilityMatrix, PbdLargeTimeStepsStayBounded) { pbdTimeStepCase(BackendKind::Cpu); }
// Known problem (reported): one long PBD substep flings the bar. Run by hand to see it.
TEST(StabilityMatrix, PbdLongFrameRefusedOrAutoSubstepped) { pbdLongSubstepCase(BackendKind::Cpu); }
TEST(StabilityMatrix, MlsCoarseToFineSpacing) { spacingCase(BackendKind::Cpu, true); }
TEST(StabilityMatrix, PbdCoarseToFineSpacing) { spacingCase(BackendKind::Cpu, false); }
TEST(StabilityMatrix, MlsJitteredRestPositions) { jitterCase(BackendKind::Cpu, true); }
TEST(StabilityMatrix, PbdJitteredRestPositions) { jitterCase(BackendKind::Cpu, false); }
TEST(StabilityMatrix, MlsCompressionUntilNeighbourhoodsInvertIsFiniteOrGuarded) {
  compressionCase(BackendKind::Cpu, true);
}
TEST(StabilityMatrix, PbdCompressionUntilNeighbourhoodsInvertIsFiniteOrGuarded) {
  compressionCase(BackendKind::Cpu, false);
}
TEST(StabilityMatrix, MlsIsolatedParticleFallsFreely) { mlsIsolatedCase(BackendKind::Cpu); }
TEST(StabilityMatrix, PbdIsolatedSphereFallsFreely) { pbdIsolatedCase(BackendKind::Cpu); }
// As many frames as fit in 3 s of wall time (CI); the 1e5-step soak is the DISABLED_ variant below.
TEST(StabilityMatrix, MlsSoak) { soakCase(BackendKind::Cpu, true, 3.0, 100000); }
TEST(StabilityMatrix, PbdSoak) { soakCase(BackendKind::Cpu, false, 3.0, 100000); }
// 1e5 PBD frames (4e5 substeps) / 1e5 MLS substeps' worth of frames: run by hand or on the GPU host,
// build/incision_tests --gtest_also_run_disabled_tests --gtest_filter='StabilityMatrix.DISABLED_*'
TEST(StabilityMatrix, DISABLED_MlsSoak100kSteps) { soakCase(BackendKind::Cpu, true, 3600.0, 100000 / 40); }
TEST(StabilityMatrix, DISABLED_PbdSoak100kSteps) { soakCase(BackendKind::Cpu, false, 3600.0, 100000); }
