#include "scene/mesh_file.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <assimp/Importer.hpp>

#include "util/files.h"
#include "util/hash.h"

// Debian builds Assimp with its assertions on (ASSIMP_BUILD_DEBUG), and a
// failed one calls this function, whose library definition aborts the
// process: a mutated OBJ trips one in the triangulation step. The penumbra
// binary, the test binary and the Python extension each export this
// definition (nm -D), and the dynamic linker searches them before
// libassimp, so the library's calls reach it instead and the file is
// refused like any other it cannot read (load_mesh_file's callers catch
// the throw).
namespace Assimp {
void aiAssertViolation(const char* expression, const char* file, int line);
void aiAssertViolation(const char* expression, const char* file, int line) {
  throw penumbra::MeshFileError(
      fmt::format("Assimp's reader failed its own check ({} at {}:{})", expression, file, line));
}
}  // namespace Assimp

namespace penumbra {

namespace {

namespace fs = std::filesystem;

// Positions, normals and UVs in double before they are welded and stored.
struct RawMesh {
  std::vector<Vec3> positions, normals;    // normals empty: the file had none
  std::vector<std::array<double, 2>> uvs;  // empty: some mesh of the file has none
  std::vector<unsigned> triangles;
};

// A mesh of the file where its node places it: the node's transform times
// its ancestors', in double (row-major, column vectors, as aiMatrix4x4),
// and the cofactor matrix that turns its normals (det M times the inverse
// transpose). Without a transform the vertices are already placed
// (aiProcess_PreTransformVertices).
struct PlacedMesh {
  const aiMesh* mesh = nullptr;
  bool transformed = false;
  double m[3][4] = {};
  double cofactor[3][3] = {};
};

PlacedMesh placed(const aiMesh* mesh, const aiMatrix4x4& t) {
  PlacedMesh out{mesh, true};
  const ai_real* row[3] = {&t.a1, &t.b1, &t.c1};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) out.m[i][j] = row[i][j];
  const auto& a = out.m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      out.cofactor[i][j] = a[i1][j1] * a[i2][j2] - a[i1][j2] * a[i2][j1];
    }
  return out;
}

Vec3 place_point(const PlacedMesh& p, const aiVector3D& v) {
  if (!p.transformed) return {v.x, v.y, v.z};
  const auto& m = p.m;
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z + m[0][3],
          m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z + m[1][3],
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z + m[2][3]};
}

// The normal turned by the inverse transpose: the cofactor matrix divided
// by det M, whose sign keeps the normal on its side under a mirroring.
Vec3 place_normal(const PlacedMesh& p, const aiVector3D& n) {
  if (!p.transformed) return {n.x, n.y, n.z};
  const auto& c = p.cofactor;
  const double det = p.m[0][0] * c[0][0] + p.m[0][1] * c[0][1] + p.m[0][2] * c[0][2];
  const Vec3 out{c[0][0] * n.x + c[0][1] * n.y + c[0][2] * n.z,
                 c[1][0] * n.x + c[1][1] * n.y + c[1][2] * n.z,
                 c[2][0] * n.x + c[2][1] * n.y + c[2][2] * n.z};
  const double l = length(out);
  return l > 0.0 ? out * (std::copysign(1.0, det) / l) : out;
}

// Every triangle of the given meshes.
RawMesh read_triangles(const std::vector<PlacedMesh>& meshes) {
  RawMesh raw;
  bool all_normals = true, all_uvs = true;
  for (const PlacedMesh& p : meshes)
    if (p.mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) {
      all_normals = all_normals && p.mesh->HasNormals();
      all_uvs = all_uvs && p.mesh->HasTextureCoords(0);
    }
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const aiMesh& mesh = *meshes[m].mesh;
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const auto first = static_cast<unsigned>(raw.positions.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      raw.positions.push_back(place_point(meshes[m], mesh.mVertices[v]));
      if (all_normals) raw.normals.push_back(place_normal(meshes[m], mesh.mNormals[v]));
      if (all_uvs) {
        const aiVector3D& uv = mesh.mTextureCoords[0][v];
        raw.uvs.push_back({uv.x, uv.y});
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh.mNumVertices)
          throw MeshFileError(fmt::format("face {} of mesh {} names vertex {} of {}", f, m,
                                          face.mIndices[k], mesh.mNumVertices));
        raw.triangles.push_back(first + face.mIndices[k]);
      }
    }
  }
  return raw;
}

// The one normal texture the read meshes' materials name, resolved against
// the mesh file's folder, or why there is none to read.
void find_normal_texture(const aiScene& scene, const std::vector<PlacedMesh>& meshes,
                         const std::string& path, MeshSurface* s) {
  std::vector<std::string> names;
  std::size_t without = 0;
  for (const PlacedMesh& p : meshes) {
    if (!(p.mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const aiMaterial* material = p.mesh->mMaterialIndex < scene.mNumMaterials
                                     ? scene.mMaterials[p.mesh->mMaterialIndex]
                                     : nullptr;
    aiString name;
    unsigned uv_set = 0;
    if (!material || material->GetTextureCount(aiTextureType_NORMALS) == 0 ||
        material->GetTexture(aiTextureType_NORMALS, 0, &name, nullptr, &uv_set) != AI_SUCCESS) {
      ++without;
      continue;
    }
    if (scene.GetEmbeddedTexture(name.C_Str()) || name.C_Str()[0] == '*') {
      s->normal_texture_why_not = fmt::format(
          "its normal texture \"{}\" is embedded in the file, which Penumbra does not "
          "read; give the image as /height/file",
          name.C_Str());
      return;
    }
    if (uv_set != 0) {
      s->normal_texture_why_not = fmt::format(
          "its normal texture \"{}\" reads texture coordinate set {}; Penumbra reads the first",
          name.C_Str(), uv_set);
      return;
    }
    if (std::find(names.begin(), names.end(), name.C_Str()) == names.end())
      names.push_back(name.C_Str());
  }
  if (names.empty())
    s->normal_texture_why_not = "its materials name no normal texture";
  else if (names.size() > 1 || without > 0)
    s->normal_texture_why_not = fmt::format(
        "its meshes name {} normal textures ({}){}; take one node (/shape/node) or give "
        "/height/file",
        names.size(), fmt::join(names, ", "), without > 0 ? " and some none" : "");
  else
    s->normal_texture = (fs::path(path).parent_path() / names[0]).lexically_normal().string();
}

// Deeper node trees are refused rather than walked (a file may nest its
// nodes without end).
constexpr int kMaxNodeDepth = 256;

// The node and those under it, depth first, with their transforms.
void collect_meshes(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent, int depth,
                    std::vector<PlacedMesh>* out) {
  if (depth > kMaxNodeDepth)
    throw MeshFileError(fmt::format("its nodes nest deeper than {}", kMaxNodeDepth));
  const aiMatrix4x4 global = parent * node.mTransformation;
  for (unsigned i = 0; i < node.mNumMeshes; ++i) {
    if (node.mMeshes[i] >= scene.mNumMeshes)
      throw MeshFileError(fmt::format("node \"{}\" names mesh {} of {}", node.mName.C_Str(),
                                      node.mMeshes[i], scene.mNumMeshes));
    out->push_back(placed(scene.mMeshes[node.mMeshes[i]], global));
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    collect_meshes(scene, *node.mChildren[c], global, depth + 1, out);
}

// The names of the first nodes, depth first, for a message.
void node_names(const aiNode& node, int depth, std::vector<std::string>* out) {
  if (out->size() >= 24 || depth > kMaxNodeDepth) return;
  if (node.mName.length > 0) out->push_back(fmt::format("\"{}\"", node.mName.C_Str()));
  for (unsigned c = 0; c < node.mNumChildren; ++c) node_names(*node.mChildren[c], depth + 1, out);
}

// The file's meshes: all of them, already placed, or those of the first
// node named `node` (depth first) and of the nodes under it, placed by
// their nodes and its ancestors.
std::vector<PlacedMesh> meshes_to_read(const aiScene& scene, const std::string& node) {
  std::vector<PlacedMesh> out;
  if (node.empty()) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) out.push_back({scene.mMeshes[m]});
    return out;
  }
  const aiNode* found = scene.mRootNode ? scene.mRootNode->FindNode(node.c_str()) : nullptr;
  if (!found) {
    std::vector<std::string> names;
    if (scene.mRootNode) node_names(*scene.mRootNode, 0, &names);
    throw MeshNodeError(
        fmt::format("no node \"{}\" in it; its nodes: {}{}", node,
                    names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", ")),
                    names.size() >= 24 ? ", ..." : ""));
  }
  aiMatrix4x4 ancestors;
  int depth = 0;
  for (const aiNode* a = found->mParent; a; a = a->mParent, ++depth) {
    if (depth > kMaxNodeDepth)
      throw MeshFileError(fmt::format("its nodes nest deeper than {}", kMaxNodeDepth));
    ancestors = a->mTransformation * ancestors;
  }
  collect_meshes(scene, *found, ancestors, 0, &out);
  return out;
}

Vec3 rotate(const Vec3& v, const Vec3& degrees_xyz) {
  const double ax = radians(degrees_xyz.x), ay = radians(degrees_xyz.y),
               az = radians(degrees_xyz.z);
  Vec3 r = v;
  r = {r.x, std::cos(ax) * r.y - std::sin(ax) * r.z, std::sin(ax) * r.y + std::cos(ax) * r.z};
  r = {std::cos(ay) * r.x + std::sin(ay) * r.z, r.y, -std::sin(ay) * r.x + std::cos(ay) * r.z};
  r = {std::cos(az) * r.x - std::sin(az) * r.y, std::sin(az) * r.x + std::cos(az) * r.y, r.z};
  return r;
}

// The index of the first vertex with each vertex's position (and normal,
// when `with_normals`): equal bits, not a tolerance, so the weld never
// merges what the file keeps apart by a hair.
std::vector<unsigned> weld(const RawMesh& raw, bool with_normals) {
  std::map<std::array<double, 6>, unsigned> first;
  std::vector<unsigned> to(raw.positions.size());
  for (std::size_t v = 0; v < raw.positions.size(); ++v) {
    const Vec3& p = raw.positions[v];
    const Vec3 n = with_normals ? raw.normals[v] : Vec3{};
    to[v] = first.emplace(std::array<double, 6>{p.x, p.y, p.z, n.x, n.y, n.z}, unsigned(v))
                .first->second;
  }
  return to;
}

// Area-weighted vertex normals over the triangles, shared by every vertex
// at one position.
std::vector<Vec3> smooth_normals(const RawMesh& raw) {
  const std::vector<unsigned> at = weld(raw, false);
  std::vector<Vec3> sum(raw.positions.size());
  for (std::size_t t = 0; t < raw.triangles.size(); t += 3) {
    const unsigned* c = &raw.triangles[t];
    // |e1 x e2| is twice the area: the cross product itself weights by area.
    const Vec3 n =
        cross(raw.positions[c[1]] - raw.positions[c[0]], raw.positions[c[2]] - raw.positions[c[0]]);
    for (int k = 0; k < 3; ++k) sum[at[c[k]]] += n;
  }
  std::vector<Vec3> out(raw.positions.size());
  for (std::size_t v = 0; v < out.size(); ++v) {
    const double l = length(sum[at[v]]);
    out[v] = l > 0.0 ? sum[at[v]] / l : Vec3{0, 0, 1};
  }
  return out;
}

// The surface's arrays from the transformed raw mesh: zero-area triangles
// dropped, vertices welded and renumbered in the order first used.
MeshSurface surface_from(const RawMesh& raw, std::size_t* dropped) {
  const std::vector<unsigned> at = weld(raw, true);
  std::vector<unsigned> number(raw.positions.size(), ~0u);
  MeshSurface s;
  TriangleMesh& m = s.mesh;
  for (std::size_t t = 0; t < raw.triangles.size(); t += 3) {
    const unsigned c[3] = {at[raw.triangles[t]], at[raw.triangles[t + 1]],
                           at[raw.triangles[t + 2]]};
    const Vec3 n =
        cross(raw.positions[c[1]] - raw.positions[c[0]], raw.positions[c[2]] - raw.positions[c[0]]);
    if (!(length_squared(n) > 0.0)) {
      ++*dropped;
      continue;
    }
    for (unsigned v : c) {
      if (number[v] == ~0u) {
        number[v] = unsigned(m.vertex_count());
        for (double x : {raw.positions[v].x, raw.positions[v].y, raw.positions[v].z})
          m.positions.push_back(float(x));
        // The file's normals as they are (Ni normalises after interpolating,
        // and a re-normalised float would not keep the file's bits).
        const Vec3 normal = raw.normals[v];
        for (double x : {normal.x, normal.y, normal.z}) m.normals.push_back(float(x));
      }
      m.triangles.push_back(number[v]);
    }
    // The corners' own UVs: the weld above ignores them.
    for (std::size_t k = 0; k < 3 && !raw.uvs.empty(); ++k)
      for (double x : raw.uvs[raw.triangles[t + k]]) s.uvs.push_back(float(x));
  }
  m.side_triangles = m.triangle_count();
  return s;
}

std::string digest_of(const MeshSurface& s) {
  const TriangleMesh& m = s.mesh;
  ContentDigest d;
  d.add(m.positions.data(), m.positions.size() * sizeof(float));
  d.add(m.normals.data(), m.normals.size() * sizeof(float));
  d.add(m.triangles.data(), m.triangles.size() * sizeof(unsigned));
  // A mesh without UVs keeps the digest it had before they were read.
  if (s.has_uvs()) d.add(s.uvs.data(), s.uvs.size() * sizeof(float));
  return d.hex();
}

// A PLY header's element counts against the bytes that follow it: every
// element takes at least one byte, so a header that claims more elements
// than that is refused before Assimp's reader, which would walk the
// claimed count (a 1e8-vertex header on an empty body spins for minutes).
void check_ply_header(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) return;
  std::uintmax_t claimed = 0;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string keyword, name;
    std::uintmax_t count = 0;
    words >> keyword;
    if (keyword == "end_header") {
      const auto body = size - std::min<std::uintmax_t>(size, std::uintmax_t(in.tellg()));
      if (claimed > body)
        throw MeshFileError(fmt::format(
            "its PLY header declares {} elements, more than the {} bytes after the header hold",
            claimed, body));
      return;
    }
    if (keyword == "element" && words >> name >> count) claimed += count;
  }
  throw MeshFileError("its PLY header has no end_header line");
}

LoadedMesh read_mesh_file(const std::string& path, const MeshTransform& transform,
                          MeshNormals normals, const std::string& node) {
  // A folder, FIFO or device is called what it is (a FIFO would block the
  // reader, /dev/zero never end).
  if (const std::string why = input_file_problem(path); !why.empty()) throw MeshFileError(why);
  std::error_code error;
  check_ply_header(path, fs::file_size(path, error));
  Assimp::Importer importer;
  // Points and lines are dropped as they are sorted out; cameras, lights
  // and animations are not read at all.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // A node is looked up in the file's own graph, which pre-transforming
  // would flatten; then its meshes are placed here.
  const unsigned flags = aiProcess_Triangulate | aiProcess_SortByPType |
                         (node.empty() ? aiProcess_PreTransformVertices : 0u) |
                         aiProcess_ValidateDataStructure;
  const aiScene* scene = importer.ReadFile(path, flags);  // may throw from aiAssertViolation
  if (!scene)
    throw MeshFileError(fmt::format("not a mesh Assimp reads: {}", importer.GetErrorString()));
  const std::vector<PlacedMesh> meshes = meshes_to_read(*scene, node);
  RawMesh raw = read_triangles(meshes);
  if (raw.triangles.size() / 3 > kMaxMeshTriangles)
    throw MeshFileError(fmt::format("{} triangles, more than the {} a mesh may have",
                                    raw.triangles.size() / 3, kMaxMeshTriangles));
  for (std::size_t v = 0; v < raw.positions.size(); ++v)
    if (!is_finite(raw.positions[v]))
      throw MeshFileError(fmt::format("vertex {} is not finite", v));
  for (Vec3& p : raw.positions)
    p = rotate(p * transform.scale, transform.rotate_deg) + transform.translate;
  for (std::size_t v = 0; v < raw.positions.size(); ++v)
    if (!is_finite(raw.positions[v]) || std::abs(raw.positions[v].x) > 1e6 ||
        std::abs(raw.positions[v].y) > 1e6 || std::abs(raw.positions[v].z) > 1e6)
      throw MeshFileError(fmt::format("vertex {} lies beyond 1e6 scene units once transformed", v));
  bool usable = !raw.normals.empty() && normals == MeshNormals::kFile;
  for (const Vec3& n : raw.normals) usable = usable && is_finite(n) && length_squared(n) > 0.0;
  if (usable)
    for (Vec3& n : raw.normals) n = rotate(n, transform.rotate_deg);
  else
    raw.normals = smooth_normals(raw);
  LoadedMesh loaded;
  MeshSurface surface = surface_from(raw, &loaded.dropped_triangles);
  if (surface.mesh.triangle_count() == 0 && !node.empty() && loaded.dropped_triangles == 0)
    throw MeshNodeError(fmt::format("node \"{}\" and the nodes under it hold no triangles", node));
  if (surface.mesh.triangle_count() == 0)
    throw MeshFileError(loaded.dropped_triangles > 0
                            ? "every triangle has zero area"
                            : "no triangles (points and lines are not surfaces)");
  for (std::size_t v = 0; v < raw.uvs.size(); ++v)
    if (!std::isfinite(raw.uvs[v][0]) || !std::isfinite(raw.uvs[v][1]))
      throw MeshFileError(fmt::format("the texture coordinates of vertex {} are not finite", v));
  if (surface.has_uvs()) surface.tangents = mikktspace_tangents(surface.mesh, surface.uvs);
  surface.digest = digest_of(surface);
  surface.file = path;
  find_normal_texture(*scene, meshes, path, &surface);
  measure_mesh(&surface);
  loaded.surface = std::make_shared<const MeshSurface>(std::move(surface));
  return loaded;
}

}  // namespace

LoadedMesh load_mesh_file(const std::string& path, const MeshTransform& transform,
                          MeshNormals normals, const std::string& node) {
  // A study reads each scene once per render job; the mesh behind them is
  // read once.
  static std::mutex mutex;
  static std::map<std::string, LoadedMesh> loaded;
  std::error_code error;
  const auto size = fs::file_size(path, error);
  const auto time = fs::last_write_time(path, error);
  const std::string key = fmt::format(
      "{}\n{}\n{}\n{:a} {:a} {:a} {:a} {:a} {:a} {:a}\n{}\n{}", path, error ? 0 : size,
      error ? 0 : time.time_since_epoch().count(), transform.scale, transform.rotate_deg.x,
      transform.rotate_deg.y, transform.rotate_deg.z, transform.translate.x, transform.translate.y,
      transform.translate.z, static_cast<int>(normals), node);
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = loaded.find(key); it != loaded.end()) return it->second;
  }
  LoadedMesh mesh = read_mesh_file(path, transform, normals, node);
  std::lock_guard<std::mutex> lock(mutex);
  if (loaded.size() > 16) loaded.clear();
  loaded[key] = mesh;
  return mesh;
}

}  // namespace penumbra

namespace penumbra {

namespace {

void write_ply_body(const TriangleMesh& mesh, const std::string& comment, CheckedFile& out) {
  const std::string header = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment {}\nelement vertex {}\nproperty float x\n"
      "property float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty "
      "float nz\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
      comment, mesh.vertex_count(), mesh.triangle_count());
  out.write(header.data(), header.size());
  std::vector<float> vertices(6 * mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    for (std::size_t k = 0; k < 3; ++k) {
      vertices[6 * v + k] = mesh.positions[3 * v + k];
      vertices[6 * v + 3 + k] = mesh.normals[3 * v + k];
    }
  out.write(vertices.data(), vertices.size() * sizeof(float));
  std::vector<unsigned char> faces(13 * mesh.triangle_count());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    faces[13 * t] = 3;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::int32_t index = std::int32_t(mesh.triangles[3 * t + k]);
      std::memcpy(&faces[13 * t + 1 + 4 * k], &index, sizeof index);
    }
  }
  out.write(faces.data(), faces.size());
}

void write_obj_body(const TriangleMesh& mesh, const std::string& comment, CheckedFile& out) {
  fmt::memory_buffer text;
  fmt::format_to(std::back_inserter(text), "# {}\n", comment);
  const std::vector<float>& p = mesh.positions;
  const std::vector<float>& n = mesh.normals;
  for (std::size_t i = 0; i < p.size(); i += 3)
    fmt::format_to(std::back_inserter(text), "v {:.9g} {:.9g} {:.9g}\n", p[i], p[i + 1], p[i + 2]);
  for (std::size_t i = 0; i < n.size(); i += 3)
    fmt::format_to(std::back_inserter(text), "vn {:.9g} {:.9g} {:.9g}\n", n[i], n[i + 1], n[i + 2]);
  // OBJ counts from 1; a vertex's normal has its index.
  for (std::size_t i = 0; i < mesh.triangles.size(); i += 3)
    fmt::format_to(std::back_inserter(text), "f {0}//{0} {1}//{1} {2}//{2}\n",
                   mesh.triangles[i] + 1, mesh.triangles[i + 1] + 1, mesh.triangles[i + 2] + 1);
  out.write(text.data(), text.size());
}

}  // namespace

void write_mesh_file(const TriangleMesh& mesh, const std::string& path,
                     const std::string& comment) {
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool ply = extension == ".ply";
  // One line in either header, whatever the caller's text (a path may hold
  // a newline).
  std::string line = comment;
  std::replace_if(
      line.begin(), line.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  write_atomically(path, [&](CheckedFile& out) {
    ply ? write_ply_body(mesh, line, out) : write_obj_body(mesh, line, out);
  });
}

}  // namespace penumbra
