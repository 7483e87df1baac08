// Writers for particles and surfaces to files ParaView and other viewers read: PLY points, legacy VTK points/meshes.
#pragma once

#include <string>
#include <vector>

#include "host/io/mesh.h"
#include "physics/vec3.h"

namespace inc {

// A named per-point scalar (e.g. "von_mises_pa", "damage"); values.size() must equal the point count.
template <typename T>
struct PointField {
  std::string name;  // letters, digits and '_' (other characters are replaced by '_' in the file)
  const std::vector<T>* values = nullptr;
};

// Binary little-endian PLY (ascii when `ascii`): element vertex with x, y, z and one scalar property per field,
// stored as float (T = float) or double (T = double). Throws InputError(path, "", reason) when the file cannot be
// written and std::invalid_argument when a field's length differs from the point count.
template <typename T>
void writePointsPly(const std::string& path, const std::vector<Vec3<T>>& positions,
                    const std::vector<PointField<T>>& fields = {}, bool ascii = false);

// Legacy VTK (version 3.0, ascii) POLYDATA: POINTS, one VERTICES cell per point, POINT_DATA scalars per field.
template <typename T>
void writePointsVtk(const std::string& path, const std::vector<Vec3<T>>& positions,
                    const std::vector<PointField<T>>& fields = {});

// Legacy VTK (version 3.0, ascii) POLYDATA: POINTS and triangle POLYGONS, POINT_DATA scalars per field.
void writeMeshVtk(const std::string& path, const TriangleMesh& mesh,
                  const std::vector<PointField<double>>& fields = {});

}  // namespace inc
