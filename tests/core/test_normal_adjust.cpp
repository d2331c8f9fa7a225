// The normal adjustments against the properties their sources state: the
// mirror direction of the view clears the surface (Cycles, Iray, Unity), the
// viewer ends up in front of the flipped normal (Mitsuba 3), Falcor's blend
// is continuous and reaches Ng at grazing views.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/normal_adjust.h"
#include "core/random.h"
#include "core/test_directions.h"

namespace penumbra {
namespace {

using test::in_plane;
using test::kZ;
using test::random_unit;
using test::spherical;

Vec3 upper(Pcg32& rng, const Vec3& n) {
  const Vec3 w = random_unit(rng);
  return dot(w, n) < 0.0 ? -w : w;
}

Vec3 mirror(const Vec3& w, const Vec3& n) {
  return n * (2.0 * dot(n, w)) - w;
}

TEST(NormalAdjust, TableIsCompleteAndIdsRoundTrip) {
  EXPECT_EQ(all_normal_adjustments().size(), 10u);
  for (const NormalAdjustmentInfo& info : all_normal_adjustments()) {
    EXPECT_EQ(normal_adjustment_from_id(info.id), info.adjustment);
    EXPECT_EQ(&normal_adjustment_info(info.adjustment), &info);
  }
  EXPECT_FALSE(normal_adjustment_from_id("iray"));
}

// Without a bump there is nothing to adjust: every adjustment returns Ng for
// every view and light above the surface.
TEST(NormalAdjust, IdentityWithoutDeviation) {
  Pcg32 rng(11);
  for (int i = 0; i < 100'000; ++i) {
    const Vec3 n = random_unit(rng), wo = upper(rng, n), wi = upper(rng, n);
    if (dot(wo, n) <= 1e-9 || dot(wi, n) <= 1e-9) continue;
    for (const NormalAdjustmentInfo& info : all_normal_adjustments()) {
      const AdjustedNormals a = adjust_normal(info.adjustment, {n, n, n, wi, wo});
      EXPECT_NEAR(length(a.ns_diffuse - n), 0.0, 1e-12) << info.id;
      EXPECT_NEAR(length(a.ns_specular - n), 0.0, 1e-12) << info.id;
      EXPECT_FALSE(a.reject_diffuse || a.reject_specular) << info.id;
    }
  }
}

// Cycles 3.6+: after the fix the mirror direction of wo lies exactly
// min(0.9 <Ng,wo>, 0.01) above the surface, the normal stays in the plane of
// Ng and Ns and turns towards Ng, and a valid normal is left alone. Blender
// 3.4's version may pick the other root of the squared equation (it keeps
// the shallower of two valid reflections), so it only promises a mirror
// direction above the surface, or Ng.
TEST(NormalAdjust, CyclesLiftsTheMirrorDirectionAboveTheThreshold) {
  Pcg32 rng(12);
  int adjusted = 0;
  for (int i = 0; i < 200'000; ++i) {
    const Vec3 ns = upper(rng, kZ), wo = upper(rng, kZ);
    if (dot(wo, ns) <= 0.0 || wo.z < 1e-3) continue;
    const double threshold = std::min(0.9 * wo.z, 0.01);
    const Vec3 n = cycles_valid_specular_normal(kZ, wo, ns);
    const Vec3 n34 = cycles34_valid_reflection_normal(kZ, wo, ns);
    ASSERT_NEAR(length(n), 1.0, 1e-12);
    ASSERT_NEAR(length(n34), 1.0, 1e-12);
    if (mirror(wo, ns).z >= threshold) {
      EXPECT_EQ(n, ns);
      EXPECT_EQ(n34, ns);
      continue;
    }
    ++adjusted;
    EXPECT_NEAR(mirror(wo, n).z, threshold, 1e-9) << wo.z << " " << ns.z;
    EXPECT_NEAR(dot(cross(kZ, ns), n), 0.0, 1e-9);  // in the plane of Ng and Ns
    EXPECT_GE(n.z, ns.z - 1e-12);                   // turned towards Ng
    if (n34 != kZ) {
      EXPECT_GE(mirror(wo, n34).z, 1e-5 * (1.0 - 1e-9));
      EXPECT_NEAR(dot(cross(kZ, ns), n34), 0.0, 1e-9);
    }
  }
  EXPECT_GT(adjusted, 1000);
}

// Iray (appendix A.3 as the public ports implement it): the bent normal's
// mirror direction of wo lands on the horizon of Ng, no lower.
TEST(NormalAdjust, IrayBendsTheMirrorDirectionOntoTheHorizon) {
  Pcg32 rng(13);
  int bent = 0;
  for (int i = 0; i < 200'000; ++i) {
    const Vec3 ns = upper(rng, kZ), wo = upper(rng, kZ);
    if (ns.z < 0.01 || dot(wo, ns) <= 0.0) continue;
    const Vec3 n = iray2017_bent_normal(kZ, ns, wo);
    if (mirror(wo, ns).z >= 0.0) {
      EXPECT_EQ(n, ns);
      continue;
    }
    ++bent;
    EXPECT_NEAR(mirror(wo, n).z, 0.0, 1e-9);
  }
  EXPECT_GT(bent, 1000);
}

// Unity HDRP: the rebuilt normal's mirror direction lies just above the
// horizon (lifted by 0.001 before normalisation); only the glossy lobe uses it.
TEST(NormalAdjust, UnityRebuildsTheSpecularNormalFromALiftedReflection) {
  Pcg32 rng(14);
  int rebuilt = 0;
  for (int i = 0; i < 200'000; ++i) {
    const Vec3 ns = upper(rng, kZ), wo = upper(rng, kZ), wi = upper(rng, kZ);
    if (wo.z < 1e-6 || dot(wo, ns) <= 0.0) continue;
    const AdjustedNormals a = adjust_normal(NormalAdjustment::kUnityHdrp, {kZ, kZ, ns, wi, wo});
    EXPECT_EQ(a.ns_diffuse, ns);
    if (mirror(wo, ns).z > 0.0) {
      EXPECT_EQ(a.ns_specular, ns);
      continue;
    }
    ++rebuilt;
    // The mirror direction of wo is the old one's horizontal part lifted
    // by 0.001 along Ng, normalised.
    const Vec3 r = mirror(wo, ns);
    const Vec3 lifted = normalize(r - kZ * r.z + kZ * 0.001);
    EXPECT_NEAR(length(mirror(wo, a.ns_specular) - lifted), 0.0, 1e-9);
  }
  EXPECT_GT(rebuilt, 1000);
}

TEST(NormalAdjust, FalcorBlendsTowardsNgAtGrazingViews) {
  const Vec3 ns = in_plane(0.6);
  // Above the threshold: untouched; at <wo,Ns> = 0.1 the blend starts at Ns.
  const Vec3 wo_far = in_plane(-0.3);
  EXPECT_EQ(falcor_adjusted_normal(kZ, ns, wo_far), ns);
  // wo = in_plane(0.6 - acos(c)) has <wo,Ns> = c.
  EXPECT_NEAR(length(falcor_adjusted_normal(kZ, ns, in_plane(0.6 - std::acos(0.1))) - ns), 0.0,
              1e-9);
  // Viewer behind Ns (but above Ng): Ng itself.
  EXPECT_NEAR(length(falcor_adjusted_normal(kZ, ns, in_plane(-1.0)) - kZ), 0.0, 1e-12);
  // Continuous: halfway through the blend, between Ng and Ns.
  const Vec3 half = falcor_adjusted_normal(kZ, ns, in_plane(0.6 - std::acos(0.05)));
  EXPECT_GT(half.z, ns.z);
  EXPECT_LT(half.z, 1.0);
}

// Mitsuba 3: where the viewer lies behind Ns but in front of Ni, the flip
// puts it in front (for Ns above the surface), keeping <Ns,Ni>.
TEST(NormalAdjust, MitsubaFlipPutsTheViewerInFront) {
  Pcg32 rng(15);
  int flipped = 0;
  for (int i = 0; i < 200'000; ++i) {
    const Vec3 ns = upper(rng, kZ), wo = upper(rng, kZ);
    if (ns.z < 1e-6 || wo.z < 1e-6) continue;
    const Vec3 n = mitsuba3_flipped_normal(kZ, ns, wo);
    EXPECT_NEAR(n.z, ns.z, 1e-12);
    if (dot(wo, ns) > 0.0) {
      EXPECT_EQ(n, ns);
      continue;
    }
    ++flipped;
    EXPECT_GT(dot(wo, n), 0.0);
  }
  EXPECT_GT(flipped, 1000);
}

TEST(NormalAdjust, CyclesHemisphereTestMatchesItsSignCondition) {
  const Vec3 ns = in_plane(0.5);
  EXPECT_FALSE(cycles_hemisphere_rejects(kZ, ns, in_plane(0.2)));
  // Light below the smooth surface but in front of Ns: a leak, rejected.
  EXPECT_TRUE(cycles_hemisphere_rejects(kZ, ns, in_plane(1.8)));
  // Light behind both: not this test's business (zero anyway).
  EXPECT_FALSE(cycles_hemisphere_rejects(kZ, ns, in_plane(-2.5)));
}

// Cycles 5.0's hemisphere test, transcribed from blender/cycles 3b1e329ac808
// src/kernel/closure/bsdf.h bump_shadowing_term (is_eval): sd->N is the smooth
// normal Ni, sc->N the closure's own normal, I the direction to the light.
//   if (isequal(sc->N, sd->N)) return 1;
//   cosNsI = dot(sd->N, I); cosNsN = dot(sd->N, sc->N); cosNI = dot(sc->N, I);
//   if (cosNsI * cosNsN * cosNI < 0) return 0;
bool cycles50_source_drops(const Vec3& sd_n, const Vec3& sc_n, const Vec3& light) {
  if (sc_n == sd_n) return false;
  return dot(sd_n, light) * dot(sd_n, sc_n) * dot(sc_n, light) < 0.0;
}

// The closures' normals as src/kernel/svm/closure.h (same commit) sets them:
// the diffuse closure keeps N (bsdf->N = N), the glossy closure gets
// maybe_ensure_valid_specular_reflection(sd, N), Cycles' 3.6+ root choice.
struct CyclesClosureNormals {
  Vec3 diffuse, glossy;
};
CyclesClosureNormals cycles50_closure_normals(const AdjustVectors& v) {
  return {v.ns, cycles_valid_specular_normal(v.ng, v.wo, v.ns)};
}

// The bumped plane of the issue: view 88 degrees off the normal, light 60
// degrees the other way, Ns tilted 40 degrees towards the viewer's opposite
// side, so that the mirror direction of wo about Ns lies below the surface
// and Cycles turns the glossy normal back towards Ng. The light is below Ns
// (<Ns,wi> = cos 100 deg < 0) but above the glossy normal: Cycles drops the
// diffuse closure and keeps the glossy one.
TEST(NormalAdjust, Cycles50TestsEachClosureWithItsOwnNormal) {
  const AdjustVectors v{kZ, kZ, in_plane(40.0 * kPi / 180.0), in_plane(-60.0 * kPi / 180.0),
                        in_plane(-88.0 * kPi / 180.0)};
  const CyclesClosureNormals n = cycles50_closure_normals(v);
  ASSERT_LT(dot(v.ns, v.wi), 0.0);
  ASSERT_GE(dot(n.glossy, v.wi), 0.0);
  ASSERT_TRUE(cycles50_source_drops(v.ni, n.diffuse, v.wi));
  ASSERT_FALSE(cycles50_source_drops(v.ni, n.glossy, v.wi));
  const AdjustedNormals a = adjust_normal(NormalAdjustment::kCycles50, v);
  EXPECT_EQ(a.ns_diffuse, n.diffuse);
  EXPECT_EQ(a.ns_specular, n.glossy);
  EXPECT_TRUE(a.reject_diffuse);
  EXPECT_FALSE(a.reject_specular);
}

// A smooth frame Ni = Ng, a bump Ns and a viewer above it, any light.
AdjustVectors random_bumped_frame(Pcg32& rng) {
  const Vec3 ni = random_unit(rng);
  const Vec3 ns = upper(rng, ni), wi = random_unit(rng), wo = upper(rng, ni);
  return {ni, ni, ns, wi, wo};
}

// The same rule on random bumped frames: each lobe is dropped exactly where
// the source drops its closure, and the sweep does reach the case where the
// glossy normal decides otherwise than Ns.
TEST(NormalAdjust, Cycles50RejectsEachLobeAsTheSourceDoes) {
  Pcg32 rng(50);
  int glossy_kept_below_ns = 0;
  for (int i = 0; i < 200'000; ++i) {
    const AdjustVectors v = random_bumped_frame(rng);
    const CyclesClosureNormals n = cycles50_closure_normals(v);
    const AdjustedNormals a = adjust_normal(NormalAdjustment::kCycles50, v);
    ASSERT_EQ(a.reject_diffuse, cycles50_source_drops(v.ni, n.diffuse, v.wi)) << i;
    ASSERT_EQ(a.reject_specular, cycles50_source_drops(v.ni, n.glossy, v.wi)) << i;
    if (cycles50_source_drops(v.ni, n.diffuse, v.wi) && !a.reject_specular) ++glossy_kept_below_ns;
  }
  EXPECT_GT(glossy_kept_below_ns, 100);
}

// Bump Map Correction off (the material's use_bump_map_correction,
// Blender 4.2+): maybe_ensure_valid_specular_reflection returns N unchanged
// without SD_USE_BUMP_MAP_CORRECTION (bsdf_util.h, same commit), so every
// closure's N is Ns, and bump_shadowing_term still runs its hemisphere test
// before the flag's early return. Each lobe is dropped exactly where the
// source drops a closure whose N is Ns.
TEST(NormalAdjust, Cycles50WithoutCorrectionKeepsNsAndTestsEveryLobeWithIt) {
  Pcg32 rng(51);
  int dropped = 0;
  for (int i = 0; i < 200'000; ++i) {
    const AdjustVectors v = random_bumped_frame(rng);
    const AdjustedNormals a = adjust_normal(NormalAdjustment::kCycles50NoCorrection, v);
    ASSERT_EQ(a.ns_diffuse, v.ns) << i;
    ASSERT_EQ(a.ns_specular, v.ns) << i;
    const bool drops = cycles50_source_drops(v.ni, v.ns, v.wi);
    ASSERT_EQ(a.reject_diffuse, drops) << i;
    ASSERT_EQ(a.reject_specular, drops) << i;
    dropped += drops;
  }
  EXPECT_GT(dropped, 1000);
}

// OSPRay's side test, transcribed from RenderKit/ospray 675c216b91a7
// modules/cpu/render/pathtracer/PathSampler.ispc, sampleDirection:
//   const bool sameSide = dot(fs.wi, pathVertex.dg.Ng) >= 0.f;
//   const bool reflection = fs.type & SCATTERING_REFLECTION;
//   if (sameSide != reflection) fs.weight = make_vec3f(0.0f);
// dg.Ng is the true geometric normal turned towards the viewer (common/
// World.ih postIntersect); Penumbra's lobes are reflections.
bool ospray_source_drops(const Vec3& dg_ng, const Vec3& wi) {
  const bool same_side = dot(wi, dg_ng) >= 0.0;
  const bool reflection = true;
  return same_side != reflection;
}

// Both signs of the disagreement between Ng and Ns, on hand-made vectors
// (Ng = z, Ns tilted 30 degrees towards +x): only Ng decides, Ns is never
// changed, and Ni (the interpolated normal) plays no part.
TEST(NormalAdjust, OsprayDropsAReflectionBelowNgWhateverNsSays) {
  const Vec3 ns = in_plane(30.0 * kPi / 180.0), wo = in_plane(-20.0 * kPi / 180.0);
  struct Case {
    const char* what;
    Vec3 ni, wi;
    bool dropped;
  };
  const Case cases[] = {
      {"above Ng and Ns", kZ, in_plane(0.5), false},
      // Ns faces the light, Ng does not: the leak OSPRay drops.
      {"below Ng, above Ns", kZ, in_plane(100.0 * kPi / 180.0), true},
      // Ng faces the light, Ns does not: kept (the BSDF gives 0 itself).
      {"above Ng, below Ns", kZ, in_plane(-70.0 * kPi / 180.0), false},
      {"on Ng's horizon (>= 0 keeps it)", kZ, Vec3{1, 0, 0}, false},
      {"below both", kZ, in_plane(-120.0 * kPi / 180.0), true},
      // Ni tilted away: the light is above Ni but below Ng, and the other way.
      {"above Ni, below Ng", in_plane(40.0 * kPi / 180.0), in_plane(95.0 * kPi / 180.0), true},
      {"below Ni, above Ng", in_plane(-40.0 * kPi / 180.0), in_plane(80.0 * kPi / 180.0), false},
  };
  for (const Case& c : cases) {
    ASSERT_EQ(ospray_source_drops(kZ, c.wi), c.dropped) << c.what;
    const AdjustedNormals a = adjust_normal(NormalAdjustment::kOspray, {kZ, c.ni, ns, c.wi, wo});
    EXPECT_EQ(a.reject_diffuse, c.dropped) << c.what;
    EXPECT_EQ(a.reject_specular, c.dropped) << c.what;
    EXPECT_EQ(a.ns_diffuse, ns) << c.what;
    EXPECT_EQ(a.ns_specular, ns) << c.what;
  }
}

TEST(NormalAdjust, OsprayRejectsExactlyWhereTheSourceDrops) {
  Pcg32 rng(40);
  int dropped = 0;
  for (int i = 0; i < 200'000; ++i) {
    const Vec3 ng = random_unit(rng);
    const AdjustVectors v{ng, random_unit(rng), random_unit(rng), random_unit(rng), upper(rng, ng)};
    const AdjustedNormals a = adjust_normal(NormalAdjustment::kOspray, v);
    const bool drops = ospray_source_drops(v.ng, v.wi);
    ASSERT_EQ(a.reject_diffuse, drops) << i;
    ASSERT_EQ(a.reject_specular, drops) << i;
    ASSERT_EQ(ospray_side_test_rejects(v.ng, v.wi), drops) << i;
    dropped += drops;
  }
  EXPECT_GT(dropped, 50'000);
}

TEST(NormalAdjust, UnitAndFiniteOnRandomAndDegenerateInputs) {
  Pcg32 rng(16);
  std::vector<AdjustVectors> cases;
  for (int i = 0; i < 1'000'000; ++i) {
    const Vec3 ng = random_unit(rng);
    cases.push_back({ng, ng, random_unit(rng), random_unit(rng), upper(rng, ng)});
  }
  const double tiny = 1e-12;
  for (const Vec3& ns : {kZ, -kZ, in_plane(kPi / 2), in_plane(tiny), in_plane(kPi / 2 + tiny)})
    for (const Vec3& w : {kZ, in_plane(kPi / 2), in_plane(-kPi / 2), in_plane(tiny), in_plane(2.0)})
      cases.push_back({kZ, kZ, ns, w, w});
  for (const AdjustVectors& v : cases)
    for (const NormalAdjustmentInfo& info : all_normal_adjustments()) {
      const AdjustedNormals a = adjust_normal(info.adjustment, v);
      ASSERT_TRUE(is_finite(a.ns_diffuse) && is_finite(a.ns_specular)) << info.id;
      ASSERT_NEAR(length(a.ns_diffuse), 1.0, 1e-9) << info.id;
      ASSERT_NEAR(length(a.ns_specular), 1.0, 1e-9) << info.id;
    }
}

}  // namespace
}  // namespace penumbra
