// Z-buffer collision of a tool tip with a point (splat) model (MFS Heller-myotomy paper, section 3).
#pragma once

#include <vector>

#include "physics/vec3.h"
#include "viewer/splat_raster.h"
#include "viewer/view_camera.h"

namespace inc::viewer {

// The paper renders the splats twice along the ray from the camera to the tool tip, once with back faces
// culled and once with front faces culled, and calls it a collision when the tip's depth lies beyond the
// front-face depth and before the back-face depth. With the nearest depth in each pass that test misses a
// tip inside the second of two lobes on the ray (the first lobe's back face is nearer than the tip). So
// both passes here are split at the tip's depth: "before" keeps the farthest surface in front of the tip
// (depth test GREATER on depths < tip), "after" the nearest surface behind it (LESS on depths >= tip).
// The tip is inside when the surface just before it faces the viewer and the one just after it faces away.
// For a ray that crosses the surface twice this is exactly the paper's test (a) and (b).
struct TipDepthBuffers {
  int width = 0, height = 0;
  double tip_depth = 0.0;            // m, view depth of the tip that split the passes
  std::vector<float> before_depth;   // m; -inf where no surface lies in front of the tip
  std::vector<float> before_facing;  // +1 front facing (normal towards the viewer), -1 back facing, 0 none
  std::vector<float> before_normal;  // 3 per pixel: the splat's world normal (unturned)
  std::vector<float> after_depth;    // m; +inf where no surface lies behind the tip
  std::vector<float> after_facing;
  std::vector<float> after_normal;
  std::size_t index(int x, int y) const { return std::size_t(y) * width + x; }
};

enum class ZView {
  ToolAxis,   // orthographic, looking along the tool shaft at the tip: independent of the user's camera
  CameraRay,  // the paper's: a narrow perspective view from the user's eye through the tip
};

// Cameras whose centre pixel's ray passes exactly through the tip (odd resolution, centre pixel centre).
// ToolAxis: eye `reach_m` behind the tip along -axis, window +-half_width_m. CameraRay: from `eye`.
ViewCamera toolAxisDepthCamera(const Vec3d& tip, const Vec3d& axis, double reach_m, double half_width_m, int res);
ViewCamera cameraRayDepthCamera(const Vec3d& eye, const Vec3d& tip, double half_width_m, double far_m, int res);

// Software rasterisation of the splats' depth into the two split buffers (the GL path fills the same struct).
void rasterizeTipDepth(const ViewCamera& cam, const SplatCloud& cloud, const Vec3d& tip, TipDepthBuffers& out);

struct ZContact {
  bool inside = false;
  double penetration_m = 0.0;   // along the view ray, from the entry surface to the tip (>= 0 when inside)
  Vec3d surface_point;          // entry point on the surface (on the ray), m
  Vec3d normal;                 // outward unit normal of the entry splat
  bool surface_before = false;  // some surface lies in front of the tip on the ray
  bool surface_after = false;
  double before_depth = 0.0, after_depth = 0.0;  // m, view depths read under the tip
};

// Reads the buffers under the tip (the centre pixel) and applies the test above.
ZContact readTipContact(const ViewCamera& cam, const TipDepthBuffers& buf, const Vec3d& tip);

// Rasterise + read, on the CPU.
ZContact zbufferCollideCpu(const ViewCamera& cam, const SplatCloud& cloud, const Vec3d& tip);

}  // namespace inc::viewer
