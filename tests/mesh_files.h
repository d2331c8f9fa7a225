// Mesh files the tests write (tests/evaluator/test_mesh_shape.cpp and the
// renderer tests' mesh scenes).
#pragma once

#include <cstdint>
#include <fstream>
#include <string>

#include "core/grid_mesh.h"

namespace penumbra {

// Writes `mesh` as a binary little-endian PLY: floats exactly as stored,
// so the file's vertices are the mesh's bits (a text format would depend
// on the reader's rounding).
inline void write_ply(const TriangleMesh& mesh, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << mesh.vertex_count()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"
         "property float ny\nproperty float nz\nelement face "
      << mesh.triangle_count() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    out.write(reinterpret_cast<const char*>(&mesh.positions[3 * v]), 3 * sizeof(float));
    out.write(reinterpret_cast<const char*>(&mesh.normals[3 * v]), 3 * sizeof(float));
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const unsigned char three = 3;
    out.write(reinterpret_cast<const char*>(&three), 1);
    for (int k = 0; k < 3; ++k) {
      const std::int32_t index = std::int32_t(mesh.triangles[3 * t + k]);
      out.write(reinterpret_cast<const char*>(&index), sizeof index);
    }
  }
}

}  // namespace penumbra
