// Assembles PBD models: a metaball organ (links, Laplacian coordinates, shape matching) and a triangle sheet (stretch +
// dihedral bending).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "host/assembly/metaball_model.h"
#include "host/compiled/model_specs.h"
#include "model/pbd_model.h"

namespace inc {

struct MetaballPbdOptions {
  double youngs_modulus_pa = 3.0e3;   // Material::youngs_modulus_pa: sets the compliances below that are left at 0
  double stretch_compliance = 0.0;    // m/N per link; 0: d_ij / (E pi rbar^2) (a rod of the spheres' mean radius)
  double laplacian_compliance = 0.0;  // m/N per sphere; 0: 1 / (E r_i)
  double shape_compliance = 0.0;      // m/N per cluster member; 0: n_j / (E r_j), n_j = clusters holding j
  double pbd_stiffness = 1.0;         // plain PBD k of every block
  bool laplacian = true;
  bool shape_matching = true;             // false: clusters kept only for the rotations skinning needs
  std::vector<FixedRegion> fixed;         // spheres whose rest centre lies inside are fixed; a box that holds no
                                          // centre is an InputError naming fixed[k] (the body would fall)
  std::string file = "metaball options";  // named in errors (the scene file when built from a scene)
  bool require_fixed_held = true;         // false: a box that holds no centre is allowed (a re-packed organ whose
                                          // clamped part was cut away: the scene was checked when it was built)
  int volume_samples = 64;                // per sphere, for the power-cell volumes (0: no volume preservation)
  // Rest power-cell volumes to reuse, one per sphere (NaN: compute; empty: compute all). A sphere's volume depends
  // only on its rest ball and its linked neighbours' balls, so one whose link set is unchanged since an earlier
  // build may pass that build's value (a cut's stroke model drops only the cut spheres: the dissection does).
  std::vector<double> known_cell_volumes;
  std::vector<ColliderSpec> colliders;  // the scene's static colliders (the model's planes and boxes)
  // With colliders: the depth (m, > 0 inside) of a point below the organ's surface, which sets each sphere's
  // PbdModel::contact_inset (radius - depth of its centre); empty: the balls themselves meet the colliders.
  std::function<double(const Vec3d&)> surface_depth;
  // Contact insets to reuse, one per sphere (NaN: compute; empty: compute all): a sphere's depends only on its rest
  // ball, so a sphere kept from an earlier build may pass that build's value (the dissection's stroke models do).
  std::vector<double> known_contact_insets;
  bool coloring = true;  // false: no Gauss-Seidel colouring (a Jacobi-only model; a cut rebuilds the
                         // model every frame the blade enters spheres, and the colouring is its
                         // largest host cost after the volumes); Gauss-Seidel on it is refused
};

// Throws InputError("metaball model", key, reason) on inconsistent or non-physical input.
template <typename T>
PbdModel<T> buildMetaballPbdModel(const MetaballModel& mb, const MetaballPbdOptions& opt);

// Spheres on a cubic lattice of `spacing` filling [lo, hi], radius radius_factor * spacing, linked when they
// overlap, mass = density * spacing^3. A stand-in organ for tests and benchmarks (beams, boxes).
MetaballModel makeLatticeMetaballs(const Vec3d& lo, const Vec3d& hi, double spacing, double radius_factor,
                                   double density);

struct SheetPbdOptions {
  double stretch_compliance = 0.0;  // m/N per edge
  double bending_compliance = 0.0;  // rad/(N m) per interior edge
  double pbd_stiffness = 1.0;
};

// Triangle mesh -> Distance block on the unique edges and Bending block on every edge shared by exactly two
// triangles (rest angles from `vertices`). Masses per vertex as given. Throws InputError on bad indices.
template <typename T>
PbdModel<T> buildSheetPbdModel(const std::vector<Vec3d>& vertices,
                               const std::vector<std::array<std::int32_t, 3>>& triangles,
                               const std::vector<double>& masses, const SheetPbdOptions& opt);

}  // namespace inc
