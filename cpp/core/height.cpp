#include "core/height.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "core/random.h"
#include "core/sin_cos.h"

namespace penumbra {

HeightSample evaluate_height(const HeightFunction& f, const Vec3& p) {
  HeightSample out;
  if (f.terms.empty()) return out;
  if (f.combine == HeightCombine::kSum) {
    for (const SineTerm& term : f.terms) {
      const SinCos sc = sin_cos(2.0 * kPi * dot(term.k, p) + term.phase);
      out.h += term.weight * sc.sin;
      out.gradient += term.k * (2.0 * kPi * term.weight * sc.cos);
    }
    return out;
  }
  // Product rule, written for the handful of factors a weave has.
  out.h = 1.0;
  double sines[kMaxProductFactors];
  double cosines[kMaxProductFactors];
  const std::size_t m = std::min<std::size_t>(f.terms.size(), kMaxProductFactors);
  for (std::size_t i = 0; i < m; ++i) {
    const SinCos sc = sin_cos(2.0 * kPi * dot(f.terms[i].k, p) + f.terms[i].phase);
    sines[i] = sc.sin;
    cosines[i] = sc.cos;
    out.h *= sines[i];
  }
  for (std::size_t i = 0; i < m; ++i) {
    double others = 1.0;
    for (std::size_t j = 0; j < m; ++j)
      if (j != i) others *= sines[j];
    out.gradient += f.terms[i].k * (2.0 * kPi * cosines[i] * others);
  }
  return out;
}

double max_abs_height(const HeightFunction& f) {
  if (f.terms.empty()) return 0.0;
  if (f.combine == HeightCombine::kProduct) return 1.0;
  double bound = 0.0;
  for (const SineTerm& term : f.terms) bound += std::abs(term.weight);
  return bound;
}

namespace {

// Each sine term's phase at the base point, as (sin, cos): the march below
// advances them by rotation, so a step costs multiplications, not sines.
struct TermPhase {
  double sin_arg = 0.0, cos_arg = 1.0;
};

// The march directions' (cos phi, sin phi), phi = 2 pi (a + 1/2) / azimuths:
// computed once, with the same std::cos and std::sin calls as per point.
struct AzimuthTable {
  double cos_phi[kVisibilityAzimuths], sin_phi[kVisibilityAzimuths];
  AzimuthTable() {
    for (int a = 0; a < kVisibilityAzimuths; ++a) {
      const double phi = 2.0 * kPi * (a + 0.5) / kVisibilityAzimuths;
      cos_phi[a] = std::cos(phi), sin_phi[a] = std::sin(phi);
    }
  }
};

// One value per march direction, as a GCC vector: element-wise IEEE
// operations at whatever width the clone compiles them to. Written out,
// because the vectoriser's choices for the plain loops changed with
// unrelated edits, down to scalar divisions.
using Lanes = double __attribute__((vector_size(kVisibilityAzimuths * sizeof(double))));

// rise[j][a] = A (h(p + d_a t_j) - h(p)) at the steps t_j = (j + 1) dt, by
// the angle-addition recurrence: per term and direction one sincos instead
// of one per step (rounding grows by about one ulp a step). The directions
// are the lanes: each performs the same IEEE operations in the same order
// as a march of its own would (the project builds with -ffp-contract=off),
// so the bits are those of one direction at a time.
using Rise = Lanes[kVisibilitySteps];
// Inlined into height_field_visibility's clones, so that it is compiled for
// each clone's vector width.
[[gnu::always_inline]] inline void march_heights(const HeightFunction& f,
                                                 std::span<const TermPhase> at_p,
                                                 const Vec3 (&d)[kVisibilityAzimuths], double dt,
                                                 double h_p, double amplitude, Rise& rise) {
  const bool sum = f.combine == HeightCombine::kSum;
  for (Lanes& row : rise) row = Lanes{} + (sum ? 0.0 : 1.0);
  for (std::size_t i = 0; i < at_p.size(); ++i) {
    Lanes cos_delta, sin_delta;
    for (int a = 0; a < kVisibilityAzimuths; ++a) {
      const double delta = 2.0 * kPi * dot(f.terms[i].k, d[a]) * dt;
      cos_delta[a] = std::cos(delta), sin_delta[a] = std::sin(delta);
    }
    Lanes s = Lanes{} + at_p[i].sin_arg, c = Lanes{} + at_p[i].cos_arg;
    const double weight = f.terms[i].weight;
    for (Lanes& row : rise) {
      const Lanes s_next = s * cos_delta + c * sin_delta;
      c = c * cos_delta - s * sin_delta;
      s = s_next;
      row = sum ? row + weight * s : row * s;
    }
  }
  for (Lanes& row : rise) row = amplitude * (row - h_p);
}

}  // namespace

// Cloned for AVX-512 and AVX2 so that the eight directions' recurrences
// and horizon divisions run in vector registers (the baseline build keeps
// them scalar). Element-wise IEEE operations without contraction
// (-ffp-contract=off) and the same libm calls: every clone gives the same
// bits.
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"))) double
height_field_visibility(const HeightFunction& f, double amplitude, const Vec3& p, const Vec3& n) {
  if (f.terms.empty() || amplitude == 0.0) return 1.0;
  double shortest_k = 0.0;
  for (const SineTerm& term : f.terms) {
    const double k = length(term.k);
    if (k > 0.0 && (shortest_k == 0.0 || k < shortest_k)) shortest_k = k;
  }
  if (shortest_k == 0.0) return 1.0;
  const double reach = 2.0 / shortest_k, dt = reach / kVisibilitySteps;
  const Frame frame = Frame::from_z(n);
  const HeightSample here = evaluate_height(f, p);
  const std::size_t m = f.combine == HeightCombine::kSum
                            ? f.terms.size()
                            : std::min<std::size_t>(f.terms.size(), kMaxProductFactors);
  TermPhase on_stack[16];
  std::vector<TermPhase> on_heap(m > 16 ? m : 0);
  const std::span<TermPhase> at_p(m > 16 ? on_heap.data() : on_stack, m);
  for (std::size_t i = 0; i < m; ++i) {
    const double arg = 2.0 * kPi * dot(f.terms[i].k, p) + f.terms[i].phase;
    at_p[i] = {std::sin(arg), std::cos(arg)};
  }
  static const AzimuthTable azimuths;
  Vec3 d[kVisibilityAzimuths];
  for (int a = 0; a < kVisibilityAzimuths; ++a)
    d[a] = frame.s * azimuths.cos_phi[a] + frame.t * azimuths.sin_phi[a];
  Rise rise;
  march_heights(f, at_p, d, dt, here.h, amplitude, rise);
  // The steepest rise seen from the displaced point, as a tangent; the
  // slope at the point itself is its limit for t -> 0, which the first
  // step would miss on a flank. The directions are the lanes of one
  // vector: the compiler left the eight divisions per step scalar.
  Lanes tan_horizon;
  for (int a = 0; a < kVisibilityAzimuths; ++a)
    tan_horizon[a] = std::max(0.0, amplitude * dot(here.gradient, d[a]));
  for (int j = 1; j <= kVisibilitySteps; ++j) {
    const Lanes tan_step = rise[j - 1] / (dt * j);
    // std::max(tan_horizon, tan_step), lane by lane.
    tan_horizon = tan_horizon < tan_step ? tan_step : tan_horizon;
  }
  // Cosine-weighted share above a horizon at elevation alpha: cos^2 alpha,
  // summed in the directions' order.
  const Lanes open_share = 1.0 / (1.0 + tan_horizon * tan_horizon);
  double open = 0.0;
  for (int a = 0; a < kVisibilityAzimuths; ++a) open += open_share[a];
  return open / kVisibilityAzimuths;
}

double max_gradient_norm(const HeightFunction& f) {
  double bound = 0.0;
  for (const SineTerm& term : f.terms)
    bound += 2.0 * kPi * length(term.k) *
             (f.combine == HeightCombine::kSum ? std::abs(term.weight) : 1.0);
  return bound;
}

double max_hessian_norm(const HeightFunction& f) {
  double bound = 0.0;
  if (f.combine == HeightCombine::kSum) {
    for (const SineTerm& term : f.terms) {
      const double w = 2.0 * kPi * length(term.k);
      bound += std::abs(term.weight) * w * w;
    }
    return bound;
  }
  // Product of sines: every second derivative is bounded by (sum_i |w_i|)^2.
  for (const SineTerm& term : f.terms) bound += 2.0 * kPi * length(term.k);
  return bound * bound;
}

HeightFunction make_grating(const Vec3& direction, double frequency, double phase) {
  return {{{normalize(direction) * frequency, phase, 1.0}}, HeightCombine::kSum};
}

HeightFunction make_weave(std::span<const Vec3> directions, double frequency,
                          HeightCombine combine) {
  HeightFunction f;
  f.combine = combine;
  for (const Vec3& d : directions) f.terms.push_back({normalize(d) * frequency, 0.0, 1.0});
  return f;
}

HeightFunction make_noise(int terms, double frequency_min, double frequency_max,
                          std::uint64_t seed) {
  HeightFunction f;
  Pcg32 rng(mix64(seed));
  const double weight = 1.0 / std::sqrt(static_cast<double>(terms));
  for (int i = 0; i < terms; ++i) {
    const double z = 1.0 - 2.0 * rng.next_double();
    const double phi = 2.0 * kPi * rng.next_double();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Vec3 direction{r * std::cos(phi), r * std::sin(phi), z};
    const double frequency = frequency_min + (frequency_max - frequency_min) * rng.next_double();
    const double phase = 2.0 * kPi * rng.next_double();
    f.terms.push_back({direction * frequency, phase, weight});
  }
  return f;
}

}  // namespace penumbra
