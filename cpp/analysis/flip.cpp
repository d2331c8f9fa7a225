#include "analysis/flip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "core/vec.h"

namespace penumbra {

namespace {

// ---- Colour matrices ----------------------------------------------------------

using Matrix3 = std::array<std::array<double, 3>, 3>;

Matrix3 inverse(const Matrix3& m) {
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
  const double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
  const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const double inv_det = 1.0 / (m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02);
  return {{{c00 * inv_det, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv_det,
            (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv_det},
           {c01 * inv_det, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv_det,
            (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv_det},
           {c02 * inv_det, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv_det,
            (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv_det}}};
}

// Linear sRGB to XYZ from the primaries' chromaticities (IEC 61966-2-1) and
// D65 at CIE's (0.31271, 0.32902), the white the reference implementation's
// matrix implies: columns (x/y, 1, (1-x-y)/y) of each primary, scaled so
// that RGB (1, 1, 1) is the white with Y = 1.
Matrix3 rgb_to_xyz_matrix() {
  const double primaries[3][2] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}};
  const double white[2] = {0.31271, 0.32902};
  Matrix3 p;
  for (int j = 0; j < 3; ++j) {
    const double x = primaries[j][0], y = primaries[j][1];
    p[0][j] = x / y, p[1][j] = 1.0, p[2][j] = (1.0 - x - y) / y;
  }
  const double w[3] = {white[0] / white[1], 1.0, (1.0 - white[0] - white[1]) / white[1]};
  const Matrix3 pi = inverse(p);
  for (int j = 0; j < 3; ++j) {
    const double s = pi[j][0] * w[0] + pi[j][1] * w[1] + pi[j][2] * w[2];
    for (int i = 0; i < 3; ++i) p[i][j] *= s;
  }
  return p;
}

std::array<double, 3> apply(const Matrix3& m, double a, double b, double c) {
  return {m[0][0] * a + m[0][1] * b + m[0][2] * c, m[1][0] * a + m[1][1] * b + m[1][2] * c,
          m[2][0] * a + m[2][1] * b + m[2][2] * c};
}

// Constants of namespace scope rather than function statics: the per-pixel
// conversions read them without a guard.
const Matrix3 kRgbToXyz = rgb_to_xyz_matrix();
const Matrix3 kXyzToRgb = inverse(kRgbToXyz);
const std::array<double, 3> kWhite = apply(kRgbToXyz, 1.0, 1.0, 1.0);

// CIELAB's f: the cube root above (6/29)^3, its tangent line below.
double lab_f(double t) {
  constexpr double delta = 6.0 / 29.0;
  return t > delta * delta * delta ? std::cbrt(t) : t / (3.0 * delta * delta) + 4.0 / 29.0;
}

}  // namespace

double pixels_per_degree(double distance_m, double width_px, double width_m) {
  return distance_m * (width_px / width_m) * (kPi / 180.0);
}

double srgb_to_linear(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

Xyz xyz_from_linear_rgb(const LinearRgb& c) {
  const auto v = apply(kRgbToXyz, c.r, c.g, c.b);
  return {v[0], v[1], v[2]};
}

LinearRgb linear_rgb_from_xyz(const Xyz& c) {
  const auto v = apply(kXyzToRgb, c.x, c.y, c.z);
  return {v[0], v[1], v[2]};
}

Xyz d65_white() {
  return {kWhite[0], kWhite[1], kWhite[2]};
}

YCxCz ycxcz_from_xyz(const Xyz& c) {
  const double x = c.x / kWhite[0], y = c.y / kWhite[1], z = c.z / kWhite[2];
  return {116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)};
}

Xyz xyz_from_ycxcz(const YCxCz& c) {
  const double y = (c.y + 16.0) / 116.0;
  return {(y + c.cx / 500.0) * kWhite[0], y * kWhite[1], (y - c.cz / 200.0) * kWhite[2]};
}

Lab lab_from_xyz(const Xyz& c) {
  const double fx = lab_f(c.x / kWhite[0]), fy = lab_f(c.y / kWhite[1]),
               fz = lab_f(c.z / kWhite[2]);
  return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

Lab hunt_adjusted(const Lab& c) {
  return {c.l, 0.01 * c.l * c.a, 0.01 * c.l * c.b};
}

double hyab(const Lab& p, const Lab& q) {
  const double da = p.a - q.a, db = p.b - q.b;
  return std::abs(p.l - q.l) + std::sqrt(da * da + db * db);
}

namespace {

const double kCmax =
    std::pow(hyab(hunt_adjusted(lab_from_xyz(xyz_from_linear_rgb({0.0, 1.0, 0.0}))),
                  hunt_adjusted(lab_from_xyz(xyz_from_linear_rgb({0.0, 0.0, 1.0})))),
             kFlipQc);

}  // namespace

double flip_max_colour_distance() {
  return kCmax;
}

double flip_colour_error(double hyab_distance) {
  const double cmax = kCmax, knee = kFlipPc * cmax;
  const double e = std::pow(hyab_distance, kFlipQc);
  // Green against blue is the largest distance in the gamut, so e <= cmax
  // and the result <= 1; the min only makes that hold by construction.
  return e < knee ? e * (kFlipPt / knee)
                  : std::min(1.0, kFlipPt + (e - knee) / (cmax - knee) * (1.0 - kFlipPt));
}

double flip_feature_error(double edge_reference, double edge_test, double point_reference,
                          double point_test) {
  const double d =
      std::max(std::abs(edge_reference - edge_test), std::abs(point_reference - point_test));
  static_assert(kFlipQf == 0.5, "the square root is x^qf");
  return std::sqrt(d / std::sqrt(2.0));
}

double flip_error(double colour_error, double feature_error) {
  return std::pow(colour_error, 1.0 - feature_error);
}

double aces_tone_map(double x) {
  // Narkowicz's fit (2.51 x^2 + 0.03 x) / (2.43 x^2 + 0.59 x + 0.14) of x
  // pre-scaled by 0.6, which undoes the fit's built-in exposure.
  const double s = 0.6 * x;
  return (2.51 * s * s + 0.03 * s) / (2.43 * s * s + 0.59 * s + 0.14);
}

// ---- Filters -------------------------------------------------------------------

namespace {

// The contrast sensitivity functions' Gaussians (a, b) per opponent channel,
// as the LDR-FLIP paper gives them (b in deg^2).
struct CsfGaussian {
  double a, b;
};
constexpr CsfGaussian kAchromatic{1.0, 0.0047}, kRedGreen{1.0, 0.0053};
constexpr CsfGaussian kBlueYellow[2] = {{34.1, 0.04}, {13.5, 0.025}};

// exp(-pi^2 x^2 / b) at x = k / ppd degrees for k in [-radius, radius]: one
// factor of the 2D Gaussian a sqrt(pi/b) exp(-pi^2 (x^2 + y^2) / b).
std::vector<double> csf_factor(double b, double ppd, int radius) {
  std::vector<double> f;
  for (int k = -radius; k <= radius; ++k) {
    const double x = k / ppd;
    f.push_back(std::exp(-kPi * kPi * x * x / b));
  }
  return f;
}

std::vector<float> scaled(const std::vector<double>& v, double s) {
  std::vector<float> out;
  for (double x : v) out.push_back(static_cast<float>(x * s));
  return out;
}

double sum(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s;
}

// Divides the positive weights by their sum and the negative ones by the
// magnitude of theirs, so that a step of height 1 gives a response of 1.
// Summed from the centre out, pairs (-k, k) together, so that the halves of
// an odd kernel get the same sum and stay exact negatives of each other.
std::vector<float> balanced(const std::vector<double>& v) {
  const std::size_t r = v.size() / 2;
  double positive = 0.0, negative = 0.0;
  auto add = [&](double x) { (x > 0.0 ? positive : negative) += std::abs(x); };
  add(v[r]);
  for (std::size_t k = 1; k <= r; ++k) add(v[r + k]), add(v[r - k]);
  std::vector<float> out;
  for (double x : v) out.push_back(static_cast<float>(x > 0.0 ? x / positive : x / negative));
  return out;
}

void check_ppd(double ppd) {
  if (!(ppd > 0.0) || !std::isfinite(ppd))
    throw std::invalid_argument(fmt::format("pixels per degree must be above 0, got {}", ppd));
}

}  // namespace

SpatialFilters spatial_filters(double ppd) {
  check_ppd(ppd);
  const double b_max = std::max({kAchromatic.b, kRedGreen.b, kBlueYellow[0].b, kBlueYellow[1].b});
  SpatialFilters f;
  f.radius = int(std::ceil(3.0 * std::sqrt(b_max / (2.0 * kPi * kPi)) * ppd));
  const std::vector<double> a = csf_factor(kAchromatic.b, ppd, f.radius);
  const std::vector<double> rg = csf_factor(kRedGreen.b, ppd, f.radius);
  f.achromatic = scaled(a, 1.0 / sum(a));
  f.red_green = scaled(rg, 1.0 / sum(rg));
  // Blue-yellow: sum_i c_i e_i(x) e_i(y) with c_i = a_i sqrt(pi / b_i); its
  // 2D sum is N = sum_i c_i (sum e_i)^2, so each pair gets sqrt(c_i / N).
  std::vector<double> e[2];
  double c[2], n = 0.0;
  for (int i = 0; i < 2; ++i) {
    e[i] = csf_factor(kBlueYellow[i].b, ppd, f.radius);
    c[i] = kBlueYellow[i].a * std::sqrt(kPi / kBlueYellow[i].b);
    n += c[i] * sum(e[i]) * sum(e[i]);
  }
  for (int i = 0; i < 2; ++i) f.blue_yellow[i] = scaled(e[i], std::sqrt(c[i] / n));
  return f;
}

FeatureFilters feature_filters(double ppd) {
  check_ppd(ppd);
  const double sigma = 0.5 * kFlipFeatureWidthDeg * ppd;
  FeatureFilters f;
  f.radius = int(std::ceil(3.0 * sigma));
  std::vector<double> g, dg, ddg;
  for (int k = -f.radius; k <= f.radius; ++k) {
    const double x = k, gx = std::exp(-x * x / (2.0 * sigma * sigma));
    g.push_back(gx);
    dg.push_back(-x * gx);                                // d/dx, without 1/sigma^2
    ddg.push_back((x * x / (sigma * sigma) - 1.0) * gx);  // d2/dx2, without 1/sigma^2
  }
  f.gaussian = scaled(g, 1.0 / sum(g));
  f.first_derivative = balanced(dg);
  f.second_derivative = balanced(ddg);
  return f;
}

int flip_support_radius(double ppd) {
  return std::max(spatial_filters(ppd).radius, feature_filters(ppd).radius);
}

// ---- Exposures ---------------------------------------------------------------------

double ExposureRange::exposure(int i) const {
  return count > 1 ? start + (stop - start) * double(i) / double(count - 1) : start;
}

namespace {

// A linear value that FLIP can use: NaN and Inf (and, for HDR, negative
// radiance) count as 0.
float sanitised(float v) {
  return std::isfinite(v) && v > 0.0f ? v : 0.0f;
}

// The luminance that exposes to 0.85 after aces_tone_map: the positive root
// of (k0 - t k3) s^2 + (k1 - t k4) s - t k5 = 0 in s = 0.6 x.
double aces_input_for(double t) {
  const double a = 2.51 - t * 2.43, b = 0.03 - t * 0.59, c = -t * 0.14;
  const double s = (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
  return s / 0.6;
}

// The element n/2 of the sorted values (the upper median), as the reference
// implementation takes it.
double upper_median(std::vector<double> v) {
  const auto middle = v.begin() + std::ptrdiff_t(v.size() / 2);
  std::nth_element(v.begin(), middle, v.end());
  return *middle;
}

}  // namespace

ExposureRange hdr_exposures(const Image& reference) {
  const int r = reference.channel_index("R"), g = reference.channel_index("G"),
            b = reference.channel_index("B");
  if (r < 0 || g < 0 || b < 0) throw ImageMismatch("FLIP needs channels R, G and B");
  const Matrix3& m = kRgbToXyz;
  std::vector<double> all, lit;
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x) {
      const double l = m[1][0] * sanitised(reference.at(x, y, r)) +
                       m[1][1] * sanitised(reference.at(x, y, g)) +
                       m[1][2] * sanitised(reference.at(x, y, b));
      all.push_back(l);
      if (l > 0.0) lit.push_back(l);
    }
  if (lit.empty()) return {0.0, 0.0, 2};
  double median = upper_median(all);
  if (!(median > 0.0)) median = upper_median(lit);
  const double x_max = aces_input_for(0.85);
  ExposureRange e;
  e.start = std::log2(x_max / *std::max_element(lit.begin(), lit.end()));
  e.stop = std::log2(x_max / median);
  e.count = std::max(2, int(std::ceil(e.stop - e.start)));
  return e;
}

// ---- The map ---------------------------------------------------------------------------

namespace {

// The buffers of planes gone, kept per thread for the next: one exposure
// makes some 35 planes, and at 128 x 128 fresh pages for each (faulted in,
// zeroed, returned) cost a fifth of the time. At most 16 MiB are kept.
struct SpareBuffers {
  std::vector<std::vector<float>> buffers;
  std::size_t bytes = 0;
};

SpareBuffers& spare_buffers() {
  thread_local SpareBuffers spare;
  return spare;
}

// One float per pixel, row-major from the top. A new plane's values are
// unspecified: every function below writes each value before reading it.
struct Plane {
  int width = 0, height = 0;
  std::vector<float> v;
  Plane(int w, int h) : width(w), height(h) {
    SpareBuffers& spare = spare_buffers();
    if (!spare.buffers.empty()) {
      v = std::move(spare.buffers.back());
      spare.buffers.pop_back();
      spare.bytes -= v.capacity() * sizeof(float);
    }
    v.resize(std::size_t(w) * std::size_t(h));
  }
  Plane(const Plane&) = default;
  Plane(Plane&&) = default;
  Plane& operator=(const Plane&) = default;
  Plane& operator=(Plane&&) = default;
  ~Plane() {
    SpareBuffers& spare = spare_buffers();
    const std::size_t bytes = v.capacity() * sizeof(float);
    if (bytes == 0 || spare.bytes + bytes > (std::size_t(16) << 20)) return;
    spare.bytes += bytes;
    spare.buffers.push_back(std::move(v));
  }
  float* row(int y) { return v.data() + std::size_t(y) * width; }
  const float* row(int y) const { return v.data() + std::size_t(y) * width; }
};

// A filter of odd length 2r + 1, even (w(-k) = w(k): the Gaussians) or odd
// (w(-k) = -w(k): the first derivative). Both fold around the centre,
// w(0) in(x) + sum over k > 0 of w(k) (in(x + k) +- in(x - k)), half the
// products; an odd filter then gives exactly 0 on a flat image.
struct Kernel {
  const std::vector<float>& w;
  bool odd;
  int radius() const { return int(w.size() / 2); }
};

// out(x, y) = the filter across row y, the edge pixel repeated outside the
// image. Cloned for AVX2 (no fused multiply-adds: -ffp-contract=off), which
// gives the bits of the default build: each pixel sums in the same order.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void filter_rows_into(
    const float* in, int width, int height, const float* w, int r, bool odd, float* padded,
    float* out) {
  for (int y = 0; y < height; ++y) {
    const float* src = in + std::size_t(y) * width;
    for (int i = 0; i < width + 2 * r; ++i) padded[i] = src[std::clamp(i - r, 0, width - 1)];
    const float* c = padded + r;
    float* dst = out + std::size_t(y) * width;
    for (int x = 0; x < width; ++x) dst[x] = w[r] * c[x];
    for (int k = 1; k <= r; ++k) {
      const float wk = w[r + k];
      if (odd)
        for (int x = 0; x < width; ++x) dst[x] += wk * (c[x + k] - c[x - k]);
      else
        for (int x = 0; x < width; ++x) dst[x] += wk * (c[x + k] + c[x - k]);
    }
  }
}

// The same down the columns, rows beyond the edge repeating the edge row.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void filter_columns_into(
    const float* in, int width, int height, const float* w, int r, bool odd, float* out) {
  auto row = [&](int y) { return in + std::size_t(std::clamp(y, 0, height - 1)) * width; };
  for (int y = 0; y < height; ++y) {
    float* dst = out + std::size_t(y) * width;
    const float* centre = row(y);
    for (int x = 0; x < width; ++x) dst[x] = w[r] * centre[x];
    for (int k = 1; k <= r; ++k) {
      const float wk = w[r + k];
      const float *below = row(y + k), *above = row(y - k);
      if (odd)
        for (int x = 0; x < width; ++x) dst[x] += wk * (below[x] - above[x]);
      else
        for (int x = 0; x < width; ++x) dst[x] += wk * (below[x] + above[x]);
    }
  }
}

Plane filter_rows(const Plane& in, const Kernel& k) {
  Plane out(in.width, in.height);
  std::vector<float> padded(std::size_t(in.width + 2 * k.radius()));
  filter_rows_into(in.v.data(), in.width, in.height, k.w.data(), k.radius(), k.odd, padded.data(),
                   out.v.data());
  return out;
}

Plane filter_columns(const Plane& in, const Kernel& k) {
  Plane out(in.width, in.height);
  filter_columns_into(in.v.data(), in.width, in.height, k.w.data(), k.radius(), k.odd,
                      out.v.data());
  return out;
}

Plane separable(const Plane& in, const std::vector<float>& w) {
  return filter_columns(filter_rows(in, {w, false}), {w, false});
}

struct RgbPlanes {
  Plane r, g, b;
};

// What LDR-FLIP reads of one image: YCxCz and the achromatic y = Y / Yn.
struct Opponent {
  Plane y, cx, cz, luminance;
};

// From linear RGB, clamped to [0, 1] first: LDR-FLIP's input range.
Opponent opponent_planes(const RgbPlanes& rgb) {
  const int w = rgb.r.width, h = rgb.r.height;
  Opponent o{Plane(w, h), Plane(w, h), Plane(w, h), Plane(w, h)};
  const double white_y = kWhite[1];
  for (std::size_t i = 0; i < rgb.r.v.size(); ++i) {
    const LinearRgb c{std::min(rgb.r.v[i], 1.0f), std::min(rgb.g.v[i], 1.0f),
                      std::min(rgb.b.v[i], 1.0f)};
    const Xyz xyz = xyz_from_linear_rgb(c);
    const YCxCz v = ycxcz_from_xyz(xyz);
    o.y.v[i] = float(v.y), o.cx.v[i] = float(v.cx), o.cz.v[i] = float(v.cz);
    o.luminance.v[i] = float(xyz.y / white_y);
  }
  return o;
}

// The image as the eye resolves it: each opponent channel through its CSF.
struct Filtered {
  Plane y, cx, cz;
};

Filtered filtered(const Opponent& o, const SpatialFilters& s) {
  Filtered f{separable(o.y, s.achromatic), separable(o.cx, s.red_green),
             separable(o.cz, s.blue_yellow[0])};
  const Plane second = separable(o.cz, s.blue_yellow[1]);
  for (std::size_t i = 0; i < f.cz.v.size(); ++i) f.cz.v[i] += second.v[i];
  return f;
}

// A filtered pixel as compared: back to linear RGB, clamped to the display's
// [0, 1] (filtering can leave it), to CIELAB, Hunt-adjusted.
Lab perceived(const Filtered& f, std::size_t i) {
  const LinearRgb c = linear_rgb_from_xyz(xyz_from_ycxcz({f.y.v[i], f.cx.v[i], f.cz.v[i]}));
  return hunt_adjusted(lab_from_xyz(xyz_from_linear_rgb(
      {std::clamp(c.r, 0.0, 1.0), std::clamp(c.g, 0.0, 1.0), std::clamp(c.b, 0.0, 1.0)})));
}

// Edge and point magnitudes: |(G' x G, G x G') * y| and |(G'' x G, G x G'') * y|.
struct Features {
  Plane edge, point;
};

Features features(const Plane& luminance, const FeatureFilters& f) {
  const Kernel g{f.gaussian, false}, d1{f.first_derivative, true}, d2{f.second_derivative, false};
  const Plane smooth_x = filter_rows(luminance, g);
  const Plane ex = filter_columns(filter_rows(luminance, d1), g);
  const Plane px = filter_columns(filter_rows(luminance, d2), g);
  const Plane ey = filter_columns(smooth_x, d1);
  const Plane py = filter_columns(smooth_x, d2);
  Features out{Plane(luminance.width, luminance.height), Plane(luminance.width, luminance.height)};
  for (std::size_t i = 0; i < ex.v.size(); ++i) {
    out.edge.v[i] = std::sqrt(ex.v[i] * ex.v[i] + ey.v[i] * ey.v[i]);
    out.point.v[i] = std::sqrt(px.v[i] * px.v[i] + py.v[i] * py.v[i]);
  }
  return out;
}

struct Filters {
  SpatialFilters spatial;
  FeatureFilters feature;
};

// LDR-FLIP of two images in linear RGB.
std::vector<float> ldr_flip(const RgbPlanes& test, const RgbPlanes& reference, const Filters& f) {
  const Opponent ot = opponent_planes(test), orf = opponent_planes(reference);
  const Filtered ft = filtered(ot, f.spatial), fr = filtered(orf, f.spatial);
  const Features et = features(ot.luminance, f.feature), er = features(orf.luminance, f.feature);
  std::vector<float> out(ot.y.v.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double colour = flip_colour_error(hyab(perceived(fr, i), perceived(ft, i)));
    const double feature =
        flip_feature_error(er.edge.v[i], et.edge.v[i], er.point.v[i], et.point.v[i]);
    out[i] = float(flip_error(colour, feature));
  }
  return out;
}

RgbPlanes rgb_planes(const Image& image) {
  const int c[3] = {image.channel_index("R"), image.channel_index("G"), image.channel_index("B")};
  RgbPlanes p{Plane(image.width, image.height), Plane(image.width, image.height),
              Plane(image.width, image.height)};
  Plane* planes[3] = {&p.r, &p.g, &p.b};
  for (int k = 0; k < 3; ++k)
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x) planes[k]->row(y)[x] = sanitised(image.at(x, y, c[k]));
  return p;
}

// 2^c times the radiance, tone mapped and clamped to [0, 1].
RgbPlanes exposed(const RgbPlanes& p, double c) {
  const double scale = std::exp2(c);
  RgbPlanes out = p;
  for (Plane* plane : {&out.r, &out.g, &out.b})
    for (float& v : plane->v) v = float(std::clamp(aces_tone_map(scale * v), 0.0, 1.0));
  return out;
}

void check_fit(const Image& test, const Image& reference) {
  for (const Image* image : {&test, &reference})
    for (const char* name : {"R", "G", "B"})
      if (image->channel_index(name) < 0)
        throw ImageMismatch(fmt::format("FLIP needs channels R, G and B; an image lacks {}", name));
  if (test.width != reference.width || test.height != reference.height)
    throw ImageMismatch(fmt::format("FLIP: the test is {}x{} but the reference {}x{}", test.width,
                                    test.height, reference.width, reference.height));
}

}  // namespace

FlipImage flip_map(const Image& test, const Image& reference, const FlipOptions& options) {
  check_fit(test, reference);
  const Filters filters{spatial_filters(options.pixels_per_degree),
                        feature_filters(options.pixels_per_degree)};
  FlipImage map;
  map.width = test.width, map.height = test.height;
  map.range = options.range;
  map.pixels_per_degree = options.pixels_per_degree;
  const RgbPlanes t = rgb_planes(test), r = rgb_planes(reference);
  if (options.range == FlipRange::kLdr) {
    map.error = ldr_flip(t, r, filters);
    return map;
  }
  // HDR-FLIP: the largest LDR-FLIP over the exposures, per pixel.
  map.exposures = options.exposures.value_or(hdr_exposures(reference));
  if (map.exposures.count < 1)
    throw std::invalid_argument(
        fmt::format("HDR-FLIP needs at least one exposure, got {}", map.exposures.count));
  map.error.assign(t.r.v.size(), 0.0f);
  for (int i = 0; i < map.exposures.count; ++i) {
    const double c = map.exposures.exposure(i);
    const std::vector<float> e = ldr_flip(exposed(t, c), exposed(r, c), filters);
    for (std::size_t k = 0; k < e.size(); ++k) map.error[k] = std::max(map.error[k], e[k]);
  }
  return map;
}

Image srgb_decoded(const Image& encoded) {
  Image out = encoded;
  for (const char* name : {"R", "G", "B"}) {
    const int c = out.channel_index(name);
    if (c < 0) continue;
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x) out.at(x, y, c) = float(srgb_to_linear(out.at(x, y, c)));
  }
  return out;
}

double mean_flip(const FlipImage& map) {
  if (map.error.empty()) return std::numeric_limits<double>::quiet_NaN();
  double s = 0.0;
  for (float e : map.error) s += e;
  return s / double(map.error.size());
}

Interval mean_flip_interval(const FlipImage& map, int bands, int resamples, std::uint64_t seed) {
  if (map.error.empty() || map.height <= 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan};
  }
  // The bands of comparison_intervals; each band's sum times (bands / N),
  // whose mean over a resample is that resample's FLIP sum over N pixels.
  const int band_rows = std::max(1, (map.height + bands - 1) / bands);
  const int count = (map.height + band_rows - 1) / band_rows;
  std::vector<double> values(std::size_t(count), 0.0);
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) values[std::size_t(y / band_rows)] += map.at(x, y);
  for (double& v : values) v *= double(count) / double(map.error.size());
  return bootstrap_mean_interval(values, 0.95, resamples, seed);
}

}  // namespace penumbra
