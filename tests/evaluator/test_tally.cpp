// The evaluator's tally of raw bump's light by factor-table cell
// (render_tallied): the image is render()'s to the bit, the tally adds up
// to it, and the tally predicts another factor method's render.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "analysis/achievable.h"
#include "analysis/metrics.h"
#include "core/terminator.h"
#include "evaluator/evaluator.h"
#include "scene/scene_json.h"

namespace penumbra {
namespace {

const std::string kScenes = std::string(PENUMBRA_SOURCE_DIR) + "/scenes";

Scene scene_with(const std::string& file, std::vector<std::string> sets) {
  std::vector<Override> overrides;
  for (const std::string& s : sets) overrides.push_back(parse_override(s));
  return load_scene(kScenes + "/" + file, overrides);
}

// Light and deviation, the inputs of estevez2019, at `step` degrees.
FactorGrid light_deviation_grid(double step) {
  return {{{FactorInput::kLight, 0.0, 180.0, step}, {FactorInput::kDeviation, 0.0, 60.0, step}}};
}

// The pixel's light as the tally splits it: rest + sum of the cells' light * g.
double tallied(const PixelTally& t, std::size_t p, auto&& g) {
  double sum = t.rest[p];
  for (std::uint32_t e = t.offsets[p]; e < t.offsets[p + 1]; ++e) sum += t.light[e] * g(t.cells[e]);
  return sum;
}

TEST(Tally, ImageIsRenderBitsAndTheTallyAddsUpToIt) {
  for (const std::vector<std::string>& sets :
       {std::vector<std::string>{"/camera/width=40", "/camera/height=40", "/camera/spp=9"},
        std::vector<std::string>{"/camera/width=40", "/camera/height=40", "/camera/spp=4",
                                 "/material/specular={\"weight\": 0.4, \"roughness\": 0.3}",
                                 "/terminator/lobes=\"diffuse\""}}) {
    const Scene scene = scene_with("sphere-grating.json", sets);
    PixelTally tally;
    const Image tallied_image = render_tallied(scene, light_deviation_grid(1.0), &tally);
    const Image plain = render(scene);
    ASSERT_EQ(tallied_image.pixels, plain.pixels);
    ASSERT_EQ(tally.offsets.size(), std::size_t(40 * 40 + 1));
    // Every pixel's light is its radiance (float channel: relative 1e-6).
    int lit = 0;
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x) {
        const std::size_t p = std::size_t(y) * 40 + std::size_t(x);
        const double radiance = plain.at(x, y, 0);
        EXPECT_NEAR(tallied(tally, p, [](int) { return 1.0; }), radiance, 1e-6 * radiance + 1e-12);
        lit += radiance > 0.0;
      }
    EXPECT_GT(lit, 200);
    // Binned as the profile bins: G = 1 is the render's own profile.
    const double scale = radiance_scale(scene);
    const ProfileTally binned = profile_tally(plain, tally, scale);
    const Profile own = terminator_profile(plain, scale);
    const Profile ones = binned.profile(std::vector<double>(std::size_t(180 * 60), 1.0));
    ASSERT_EQ(ones.count, own.count);
    for (std::size_t b = 0; b < own.value.size(); ++b)
      EXPECT_NEAR(ones.value[b], own.value[b], 1e-6 * std::abs(own.value[b]) + 1e-12) << b;
  }
}

// estevez2019's G depends on the light and deviation alone: its table at
// the cells' centres, applied to raw bump's tally, is its own render, up to
// how much G varies within a cell. That error shrinks as the cells do.
TEST(Tally, PredictsAFactorMethodsRenderToTheGridsResolution) {
  const Scene bump = scene_with("cylinder-grating.json",
                                {"/camera/width=48", "/camera/height=48", "/camera/spp=4",
                                 "/height/amplitude=0.02", "/light/direction=[-1, 0, 0.4]"});
  Scene estevez = bump;
  estevez.terminator.method.method = TerminatorMethod::kEstevez2019;
  const Image truth = render(estevez);
  const auto g_at = [](double light_deg, double deviation_deg) {
    const double l = light_deg * M_PI / 180.0, d = deviation_deg * M_PI / 180.0;
    const Vec3 ng{0, 0, 1}, ns{std::sin(d), 0, std::cos(d)}, wi{std::sin(l), 0, std::cos(l)};
    return terminator_factor(MethodSettings{TerminatorMethod::kEstevez2019}, ng, ns, wi, wi);
  };
  std::vector<double> errors;
  for (const double step : {4.0, 1.0, 0.25}) {
    const FactorGrid grid = light_deviation_grid(step);
    PixelTally tally;
    render_tallied(bump, grid, &tally);
    std::vector<double> table(std::size_t(grid.cells()));
    for (int c = 0; c < grid.cells(); ++c) {
      const std::vector<double> centre = grid.centre(c);
      table[std::size_t(c)] = g_at(centre[0], centre[1]);
    }
    double sum = 0.0, reference = 0.0;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x) {
        const std::size_t p = std::size_t(y) * 48 + std::size_t(x);
        const double predicted = tallied(tally, p, [&](int c) { return table[std::size_t(c)]; });
        sum += std::abs(predicted - truth.at(x, y, 0));
        reference += truth.at(x, y, 0);
      }
    errors.push_back(sum / reference);
  }
  // Relative mean absolute error: below 1 % at 1 degree, and falling with
  // the cell size (G is smooth, so about linearly).
  EXPECT_LT(errors[1], 0.01) << errors[0] << " " << errors[1] << " " << errors[2];
  EXPECT_LT(errors[2], 0.5 * errors[1]);
  EXPECT_LT(errors[1], 0.5 * errors[0]);
}

// A tally on a grid with a shading axis over every angle, summed over that
// axis (marginal_tally), is the tally of the grid without it: each
// sample's shading weights sum to one, so only the order of the additions
// differs (relative 1e-12). What penumbra fit's nested floors stand on.
TEST(Tally, SummedOverAnAxisThatSpansEveryAngleIsTheTallyWithoutIt) {
  const Scene scene = scene_with("sphere-weave.json", {"/camera/width=40", "/camera/height=40",
                                                       "/camera/spp=4", "/height/amplitude=0.02"});
  const FactorGrid plain = {
      {{FactorInput::kLight, 20.0, 120.0, 4.0}, {FactorInput::kDeviation, 0.0, 60.0, 6.0}}};
  FactorGrid shading = plain;
  shading.axes.push_back({FactorInput::kShading, 0.0, 180.0, 12.0});
  PixelTally with_plain, with_shading;
  const Image image = render_tallied(scene, plain, &with_plain);
  render_tallied(scene, shading, &with_shading);
  const double scale = radiance_scale(scene);
  const ProfileTally direct = profile_tally(image, with_plain, scale);
  const ProfileTally summed =
      marginal_tally(profile_tally(image, with_shading, scale), shading, plain);
  ASSERT_EQ(summed.count, direct.count);
  std::size_t entries = 0;
  for (std::size_t b = 0; b < direct.count.size(); ++b) {
    EXPECT_NEAR(summed.rest[b], direct.rest[b], 1e-12 * (1.0 + direct.rest[b])) << b;
    ASSERT_EQ(summed.scaled[b].size(), direct.scaled[b].size()) << b;
    for (std::size_t e = 0; e < direct.scaled[b].size(); ++e) {
      EXPECT_EQ(summed.scaled[b][e].first, direct.scaled[b][e].first) << b;
      EXPECT_NEAR(summed.scaled[b][e].second, direct.scaled[b][e].second,
                  1e-12 * (1.0 + direct.scaled[b][e].second))
          << b;
    }
    entries += direct.scaled[b].size();
  }
  EXPECT_GT(entries, 100u) << "too little light in the grid: the test shows nothing";
  // The shading axis split the light: the unsummed tally has more cells.
  std::size_t split = 0;
  for (const auto& bin : profile_tally(image, with_shading, scale).scaled) split += bin.size();
  EXPECT_GT(split, entries);
  // Only a grid made of the source's axes is a marginal of it.
  FactorGrid other = plain;
  other.axes[0].step_deg = 2.0;
  EXPECT_THROW(marginal_tally(direct, plain, other), std::invalid_argument);
}

// What penumbra fit optimises is what the fitted method renders: a table's
// prediction through raw bump's tally is the `fitted` render of that table
// (float channel: relative 1e-6), on the fit's default grid, with a GGX
// lobe the factor leaves alone, and the light at both of the default
// study's directions.
TEST(Tally, FittedMethodRendersWhatTheTallyPredicts) {
  const FactorGrid grid{
      {{FactorInput::kLight, 20.0, 120.0, 2.0}, {FactorInput::kDeviation, 0.0, 60.0, 4.0}}};
  auto table = std::make_shared<FactorTable>();
  table->grid = grid;
  for (int c = 0; c < grid.cells(); ++c)  // smooth in both angles, in [0.1, 1.9]
    table->values.push_back(1.0 + 0.9 * std::sin(0.07 * c) * std::cos(0.002 * c * c));
  for (const char* light : {"/light/direction=[-1, 0, -0.2]", "/light/direction=[-1, 0, 0.4]"}) {
    const Scene bump = scene_with("sphere-weave.json",
                                  {"/camera/width=40", "/camera/height=40", "/camera/spp=4", light,
                                   "/material/specular={\"weight\": 0.4, \"roughness\": 0.3}",
                                   "/terminator/lobes=\"diffuse\""});
    PixelTally tally;
    render_tallied(bump, grid, &tally);
    Scene fitted = bump;
    fitted.terminator.method = {TerminatorMethod::kFitted, 0.0, table};
    const Image image = render(fitted);
    const Image raw = render(bump);
    int differ = 0;
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x) {
        const std::size_t p = std::size_t(y) * 40 + std::size_t(x);
        const double predicted =
            tallied(tally, p, [&](int c) { return table->values[std::size_t(c)]; });
        EXPECT_NEAR(predicted, image.at(x, y, 0), 1e-6 * image.at(x, y, 0) + 1e-12)
            << x << "," << y;
        differ += std::abs(image.at(x, y, 0) - raw.at(x, y, 0)) > 1e-3;
      }
    EXPECT_GT(differ, 50) << "the table changed too few pixels to test anything";
  }
}

// A table of ones is raw bump to the bit; a table of halves over every
// angle halves a Lambertian render exactly (a power of two scales each
// sample's light without rounding).
TEST(Tally, FittedTablesOfConstantsAreExact) {
  const Scene bump = scene_with("cylinder-grating.json",
                                {"/camera/width=32", "/camera/height=32", "/camera/spp=4"});
  const Image none = render(bump);
  for (const double g : {1.0, 0.5}) {
    auto table = std::make_shared<FactorTable>();
    table->grid = {
        {{FactorInput::kLight, 0.0, 180.0, 10.0}, {FactorInput::kDeviation, 0.0, 180.0, 10.0}}};
    table->values.assign(std::size_t(table->grid.cells()), g);
    Scene fitted = bump;
    fitted.terminator.method = {TerminatorMethod::kFitted, 0.0, table};
    const Image image = render(fitted);
    for (std::size_t i = 0; i < none.pixels.size(); i += none.channels.size())
      ASSERT_EQ(image.pixels[i], float(g) * none.pixels[i]) << i;
  }
}

// Factor probes (FactorProbe): a probe of a factor method's factors at
// several values gives, on each pixel it is tried on, the radiance of a
// render of the method at each value (float channel: relative 1e-6), with
// the light of the lobes the method scales (shading-offset the scene's,
// micro-shadowing all of them, with the height field's visibility, which
// no pass of raw bump reads); the pixels it is not tried on stay 0; and the
// tallied image keeps render()'s bits.
TEST(Tally, ProbesRenderWhatTheirMethodRenders) {
  const Scene bump =
      scene_with("sphere-weave.json", {"/camera/width=24", "/camera/height=24", "/camera/spp=4",
                                       "/material/specular={\"weight\": 0.4, \"roughness\": 0.3}",
                                       "/terminator/lobes=\"diffuse\""});
  const std::vector<double> s_values{0.0, 0.4, 0.9};
  TallyProbes probes;
  probes.probes.push_back(
      {Lobes::kDiffuse, false, s_values.size(), [&](const ShadingPoint& p, double* out) {
         for (std::size_t k = 0; k < s_values.size(); ++k)
           out[k] = shading_offset(s_values[k], p.ns, p.wi);
       }});
  probes.probes.push_back({Lobes::kAll, true, 1, [](const ShadingPoint& p, double* out) {
                             out[0] = microshadow_chan2018(dot(p.ns, p.wi), p.visibility, 2.0);
                           }});
  // Every other pixel.
  probes.pixels.assign(24 * 24, 0);
  for (std::size_t p = 0; p < probes.pixels.size(); p += 2) probes.pixels[p] = 1;
  PixelTally tally;
  const Image image = render_tallied(bump, light_deviation_grid(1.0), &tally, {}, nullptr, &probes);
  ASSERT_EQ(image.pixels, render(bump).pixels);
  std::vector<std::pair<Image, const double*>> expected;
  for (std::size_t k = 0; k < s_values.size(); ++k) {
    Scene s = bump;
    s.terminator.method = {TerminatorMethod::kShadingOffset, s_values[k]};
    expected.emplace_back(render(s), probes.radiance[0].data() + k);
  }
  Scene chan = bump;
  chan.terminator.method.method = TerminatorMethod::kMicroshadowChan2018;
  expected.emplace_back(render(chan), probes.radiance[1].data());
  int darker = 0;
  for (std::size_t e = 0; e < expected.size(); ++e) {
    const std::size_t values = e < s_values.size() ? s_values.size() : 1;
    for (std::size_t p = 0; p < probes.pixels.size(); ++p) {
      const double probe = expected[e].second[p * values];
      const double rendered = expected[e].first.pixels[p * image.channels.size()];
      if (!probes.pixels[p]) {
        EXPECT_EQ(probe, 0.0) << p;
        continue;
      }
      EXPECT_NEAR(probe, rendered, 1e-6 * rendered + 1e-12) << e << " " << p;
      darker += rendered < image.pixels[p * image.channels.size()] * (1.0 - 1e-3);
    }
  }
  EXPECT_GT(darker, 50);  // the factors act: not raw bump in disguise
}

// The tally through packets (PacketRows), where a packet runs on across
// pixels, is the scalar path's to the bit: each pixel's cells, light and
// rest, and every probe's radiance, with a probe that reads the height
// field's visibility on some pixels only. Otherwise the fit's tallies
// would depend on whether the machine traced in packets.
TEST(Tally, PacketsAndTheScalarPathTallyTheSameBits) {
  for (const std::vector<std::string>& sets :
       {std::vector<std::string>{"/camera/width=24", "/camera/height=20", "/camera/spp=9",
                                 "/material/specular={\"weight\": 0.4, \"roughness\": 0.3}",
                                 "/terminator/lobes=\"diffuse\""},
        std::vector<std::string>{"/camera/width=30", "/camera/height=16", "/camera/spp=4",
                                 "/light/direction=[-1, 0, 0.4]"}}) {
    for (const char* file : {"sphere-weave.json", "cylinder-grating.json"}) {
      const Scene bump = scene_with(file, sets);
      const auto probed = [&](bool packets, RenderStats* stats, TallyProbes* probes) {
        probes->probes.push_back(
            {Lobes::kDiffuse, false, 2, [](const ShadingPoint& p, double* out) {
               out[0] = shading_offset(0.2, p.ns, p.wi);
               out[1] = shading_offset(0.7, p.ns, p.wi);
             }});
        probes->probes.push_back({Lobes::kAll, true, 1, [](const ShadingPoint& p, double* out) {
                                    out[0] =
                                        microshadow_chan2018(dot(p.ns, p.wi), p.visibility, 2.0);
                                  }});
        probes->pixels.assign(std::size_t(bump.camera.width * bump.camera.height), 0);
        for (std::size_t p = 0; p < probes->pixels.size(); p += 3) probes->pixels[p] = 1;
        RenderOptions options;
        options.packets = packets;
        PixelTally tally;
        const Image image =
            render_tallied(bump, light_deviation_grid(1.0), &tally, options, stats, probes);
        return std::make_pair(image, tally);
      };
      RenderStats packet_stats, scalar_stats;
      TallyProbes packet_probes, scalar_probes;
      const auto [packet_image, packet_tally] = probed(true, &packet_stats, &packet_probes);
      const auto [scalar_image, scalar_tally] = probed(false, &scalar_stats, &scalar_probes);
      ASSERT_TRUE(packet_stats.packets) << file << ": the packet path was not taken";
      ASSERT_FALSE(scalar_stats.packets) << file;
      EXPECT_EQ(packet_image.pixels, scalar_image.pixels) << file;
      EXPECT_EQ(packet_tally.offsets, scalar_tally.offsets) << file;
      EXPECT_EQ(packet_tally.cells, scalar_tally.cells) << file;
      EXPECT_EQ(packet_tally.light, scalar_tally.light) << file;
      EXPECT_EQ(packet_tally.rest, scalar_tally.rest) << file;
      ASSERT_EQ(packet_probes.radiance.size(), 2u);
      EXPECT_EQ(packet_probes.radiance, scalar_probes.radiance) << file;
      int probed_lit = 0;
      for (double r : packet_probes.radiance[1]) probed_lit += r > 0.0;
      EXPECT_GT(probed_lit, 20) << file << ": too few probed pixels lit to test anything";
    }
  }
}

TEST(Tally, RefusesAnythingButRawBump) {
  Scene scene = scene_with("sphere-grating.json", {"/camera/width=8", "/camera/height=8"});
  scene.terminator.method.method = TerminatorMethod::kChiang2019;
  PixelTally tally;
  EXPECT_THROW(render_tallied(scene, light_deviation_grid(1.0), &tally), std::invalid_argument);
}

}  // namespace
}  // namespace penumbra
