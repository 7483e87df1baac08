// Tip stiffness of the MFS local model (condensed once) and the probe contact on a tissue plane.
#include "host/haptics/tip_contact.h"

#include <cmath>
#include <vector>

#include "model/input_error.h"

namespace inc {

TipStiffness mfsTipStiffness(const Material& material, double radius_m, double spacing_m, const Vec3d& n) {
  const char* f = "<tip stiffness>";
  if (!(radius_m > 0.0) || !(spacing_m > 0.0) || !(spacing_m <= 0.5 * radius_m))
    throw InputError(f, "local_spacing_m", "needs 0 < spacing <= radius / 2");
  if (!(std::fabs(norm(n) - 1.0) <= 1e-6)) throw InputError(f, "surface_normal", "must be a unit vector");
  HemisphereCloudSpec spec;
  spec.inner_spacing_m = spacing_m;
  spec.inner_shells = 2;
  spec.radius_m = radius_m;
  const std::shared_ptr<MfsLocalModel> model = mfsTipModel(spec, material, false);
  const Eigen::MatrixXd& s = model->condensedAA();  // local frame: z = outward normal
  // World frame R = [t1 t2 n]: K_world = R S R^T.
  const Vec3d helper = std::fabs(n.z) < 0.9 ? Vec3d{0, 0, 1} : Vec3d{1, 0, 0};
  const Vec3d t1 = cross(helper, n) * (1.0 / norm(cross(helper, n)));
  const Vec3d t2 = cross(n, t1);
  const Vec3d axes[3] = {t1, t2, n};
  TipStiffness out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double v = 0.0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) v += axes[a][i] * s(a, b) * axes[b][j];
      out.k_n_per_m[i][j] = v;
    }
  return out;
}

CuttingTool::Elastic tipElastic(const TipStiffness& tip) {
  return [tip](const TipContact& c) {
    ForceResult r;
    if (c.in_contact) r.force_n = tip.handForce(c.displacement_m);
    return r;
  };
}

ProbeTool::ProbeTool(CuttingTool::Elastic elastic, const Vec3d& surface_point_m, const Vec3d& unit_normal)
    : elastic_(std::move(elastic)), surface_(surface_point_m), normal_(unit_normal) {
  if (!elastic_) throw InputError("<probe tool>", "elastic", "no elastic force model");
  if (!isFinite(surface_point_m)) throw InputError("<probe tool>", "surface_point_m", "must be finite");
  if (!(std::fabs(norm(unit_normal) - 1.0) <= 1e-6))
    throw InputError("<probe tool>", "normal", "must be a unit vector");
}

ForceResult ProbeTool::tick(const ForceRequest& q) {
  const Vec3d p = q.sample.position_m;
  const double depth = -dot(p - surface_, normal_);
  if (!(depth > 0.0)) {
    in_contact_ = false;
    (void)elastic_(TipContact{});  // the elastic model hears that the contact ended; no force out of the tissue
    return ForceResult{};
  }
  if (!in_contact_) anchor_ = p + normal_ * depth;  // where the tip entered, on the plane
  in_contact_ = true;
  return elastic_(TipContact{true, anchor_, p - anchor_});
}

}  // namespace inc
