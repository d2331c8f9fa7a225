// Triangle meshes from files, read with Assimp (Debian's libassimp-dev): the
// formats Assimp reads (OBJ, PLY, glTF 2.0, Collada and more; OBJ and PLY
// are the ones the tests write and read). Every mesh of the file is taken
// with its nodes' transforms applied, polygons triangulated, points and
// lines dropped, and vertices that share a position and a normal welded, so
// that the ground truth's subdivision is watertight wherever the file's
// normals are shared (a UV seam does not split the surface; a hard edge,
// where the file gives one position two normals, does, as in every
// renderer that displaces along the normal).
#pragma once

#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>

#include "core/enum_names.h"
#include "core/mesh_surface.h"
#include "core/vec.h"

namespace penumbra {

enum class MeshNormals {
  kFile,    // the file's vertex normals; generated smooth where it has none
  kSmooth,  // always generated: area-weighted means over the welded vertices
};
inline constexpr EnumName<MeshNormals> kMeshNormalsNames[] = {{"file", MeshNormals::kFile},
                                                              {"smooth", MeshNormals::kSmooth}};

// p' = R (scale p) + translate, with R = Rz Ry Rx of rotate_deg (x turned
// first; degrees, right-handed about each axis as POV-Ray's `rotate`);
// normals turn by R. Scale is uniform, so normals need no inverse transpose.
struct MeshTransform {
  double scale = 1.0;  // > 0
  Vec3 rotate_deg;
  Vec3 translate;  // scene units
};

// More triangles than this are refused before they are read into the
// evaluator's arrays (about 60 bytes each with the BVH).
inline constexpr std::size_t kMaxMeshTriangles = 20'000'000;

// What is wrong with a mesh file, without its path (the scene reader adds
// the file and the JSON pointer).
class MeshFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// The node asked for is not in the file (the reader adds /shape/node).
class MeshNodeError : public MeshFileError {
 public:
  using MeshFileError::MeshFileError;
};

// The mesh at `path`, transformed; triangles of zero area are dropped (the
// count is in dropped_triangles). Loaded once per path, size, time and
// settings in a process, as image maps are. MeshFileError when the file is
// missing or unreadable, has no triangle left, a vertex that is not finite,
// or too many triangles.
// `node`, when not empty, names a node of the file's scene graph (a glTF
// or Collada node, an OBJ object): only the meshes of that node and of the
// nodes under it are read, each with its node's transform times its
// ancestors' (where it sits in the whole file), normals by the inverse
// transpose, normalised. MeshNodeError when no node has that name, or when
// it holds no triangle; the message lists the file's node names.
struct LoadedMesh {
  std::shared_ptr<const MeshSurface> surface;
  std::size_t dropped_triangles = 0;
};
LoadedMesh load_mesh_file(const std::string& path, const MeshTransform& transform,
                          MeshNormals normals, const std::string& node = "");

// Writes `mesh` (vertices, their normals, triangles) to `path` whole or not
// at all: binary little-endian PLY holds the floats' bits; OBJ writes each
// with 9 significant digits, which a correctly rounding reader turns back
// into the same float. `comment` heads the file (newlines become spaces).
// The format is the extension's (".obj" or ".ply"); std::runtime_error
// when the file cannot be written.
void write_mesh_file(const TriangleMesh& mesh, const std::string& path, const std::string& comment);

}  // namespace penumbra
