// A height map integrated from a tangent-space normal map, so that a
// normal-mapped asset has a displaced surface to be measured against: the
// least-squares (Poisson) integration of the map's slopes on its texel
// grid (Frankot and Chellappa 1988 solve the same problem in Fourier space
// for periodic maps; here conjugate gradients on the grid Laplacian, which
// serves both periodic and clamped edges). A normal map need not be the
// normal of any height field: the part of its slope field that is not a
// gradient (its curl) cannot be displaced, and is reported as the angle
// between the map's normals and the integrated height's.
// Pure math: the CLI reads and writes the images.
#pragma once

#include <vector>

#include "core/surface_map.h"

namespace penumbra {

// Normals within this cosine of the tangent plane are clamped to it before
// their slope -n_x / n_z is taken (about 87 degrees: a steeper slope says
// more about the map's encoding than about a surface).
inline constexpr double kMinNormalZ = 0.05;

struct IntegratedHeight {
  int width = 0, height = 0;
  // Scene units, row-major from the top row as the map's texels, mean 0:
  // the H with A = 1 whose bump normal n = normalize(-dH/dx, -dH/dy, 1)
  // (x along +u, y along +v, in scene units) the map encodes.
  std::vector<float> heights;
  double rms_angle_deg = 0.0;      // between the map's normals and H's, over the texels
  double largest_angle_deg = 0.0;  // the same, at its largest
  int clamped = 0;                 // texels whose n_z was raised to kMinNormalZ
  int iterations = 0;              // of conjugate gradients
  bool converged = false;          // the residual fell to 1e-10 of the right side's
};

// More texels than this are refused by the CLI: the solve holds about 56
// bytes a texel (4096 x 4096: about 0.9 GiB).
inline constexpr long long kMaxIntegratedTexels = 4096LL * 4096LL;

// `map` a kNormal map spanning length_u by length_v scene units (the scene
// length of its u and v lines: a plane's sides, a sphere's equator and half
// meridian, a mesh's mean UV scale); its edge mode decides whether the
// integration wraps (kWrap) or not. Slopes are taken at texels and averaged
// onto the edges between them; the result is exact for a map of exact
// normals up to that averaging, a relative slope error of (omega tau)^2 / 12
// for a sine of angular frequency omega at texel pitch tau.
IntegratedHeight integrate_normal_map(const SurfaceMap& map, double length_u, double length_v);

}  // namespace penumbra
