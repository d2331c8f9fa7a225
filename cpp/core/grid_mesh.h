// A shape's displaceable surface as a regular (u, v) grid of triangles, with
// the exact (displaced) normal at every vertex. The ground-truth tracer and
// the Blender export share it, so both see the same triangles.
//
// Layout (the tracer decodes primitive ids from it instead of storing them):
//  cylinder side: vertex (i, j) = j*nu + i, i in [0, nu) wrapping around,
//    j in [0, nv]; quad (i, j) -> triangles 2 (j nu + i) + {0, 1};
//    caps, if any, follow as two fans (bottom, then top) around centre
//    vertices, with their own rim vertices so that their normals stay flat.
//  sphere: pole 0, rings j = 1..nv-1 at 1 + (j-1) nu + i, pole last;
//    triangles: top fan [0, nu), quads, bottom fan.
//  plane: vertex (i, j) = j*(nu+1) + i, i in [0, nu], j in [0, nv]; quad
//    (i, j) -> triangles 2 (j nu + i) + {0, 1}, split as the cylinder's.
#pragma once

#include <cstddef>
#include <vector>

#include "core/height.h"
#include "core/shape.h"
#include "core/surface_map.h"

namespace penumbra {

struct GridResolution {
  unsigned nu = 0;  // segments around (azimuth), or along the plane's width
  unsigned nv = 0;  // segments along the axis (cylinder), pole to pole (sphere), the plane's height
};

// Segments so that no edge of the displaced grid is much longer than `edge`
// (scene units, > 0); `reach` = A max|h|.
GridResolution grid_resolution(const Shape& shape, double edge, double reach);

// Whether make_grid_mesh fills TriangleMesh::normals. The ground-truth tracer
// takes its normals from the analytic surface, so it skips them: at the
// finest edge they are 100 MiB it would never read.
enum class GridNormals { kExact, kOmit };

struct TriangleMesh {
  std::vector<float> positions;     // 3 per vertex, scene units
  std::vector<float> normals;       // 3 per vertex, unit; empty with GridNormals::kOmit
  std::vector<unsigned> triangles;  // 3 vertex indices per triangle
  std::size_t side_triangles = 0;   // triangles before the cylinder caps
  std::size_t vertex_count() const { return positions.size() / 3; }
  std::size_t triangle_count() const { return triangles.size() / 3; }
};

// The displaced surface P + A h(P) N(P) (A = 0: the base surface), its
// vertex normals the exact normals of that surface; h is the height map
// `map` where one is given (height_at), else `height`. Shape must carry its
// frame (with_frame). Rows of vertices are computed in parallel (TBB, in the
// caller's task arena); every vertex depends on its (u, v) alone, so the
// bits do not depend on the thread count.
TriangleMesh make_grid_mesh(const Shape& shape, const HeightFunction& height, double amplitude,
                            GridResolution resolution, const SurfaceMap* map = nullptr,
                            GridNormals normals = GridNormals::kExact);

// Grid parameters (surface_at's u and v) of vertex column i and row j (see
// the layout above).
double grid_u(const Shape& shape, GridResolution r, unsigned i);
double grid_v(const Shape& shape, GridResolution r, unsigned j);

}  // namespace penumbra
