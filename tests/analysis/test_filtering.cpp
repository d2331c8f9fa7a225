// The bump-filtering experiment: properties that hold whatever the map
// (a footprint of one texel is its own reference; a flat map needs no
// filter), Schilling's claim that plain mip-mapping loses the roughness,
// determinism, and the command line's files and refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "analysis/filtering.h"
#include "cli_test.h"
#include "core/random.h"
#include "image/image_io.h"
#include "temp_dir_test.h"

namespace penumbra {
namespace {

// Random heights smoothed over 2 texels: slopes with a standard deviation
// of ~0.2, bumps that a few levels of the pyramid average away.
std::vector<float> bumpy_heights(int n, std::uint64_t seed) {
  Pcg32 rng(seed);
  std::vector<float> white(n * n), smooth(n * n);
  for (float& h : white) h = float(rng.next_double());
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      double sum = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) sum += white[((y + dy + n) % n) * n + (x + dx + n) % n];
      smooth[y * n + x] = float(sum / 9.0);
    }
  return smooth;
}

std::vector<PyramidLevel> pyramid_of(const std::vector<float>& heights, int n, double scale) {
  return build_bump_pyramid(offsets_from_heights(heights, n, n, 1.0, scale, MapEdge::kWrap));
}

FilteringOptions small_options() {
  FilteringOptions o;
  o.alphas = {0.05, 0.3};
  o.max_level = 4;
  o.footprints = 12;
  o.sweep_step_deg = 1.0;
  o.jobs = 2;
  return o;
}

const FilteringCell& cell(const FilteringResult& r, RoughnessFilter f, double alpha, int level) {
  for (const FilteringCell& c : r.cells)
    if (c.filter == f && c.alpha == alpha && c.level == level) return c;
  throw std::logic_error("no such cell");
}

TEST(Filtering, OneTexelFootprintsAndFlatMapsNeedNoFilter) {
  const int n = 32;
  const FilteringResult bumpy =
      run_filtering_experiment(pyramid_of(bumpy_heights(n, 1), n, 1.0), small_options());
  const FilteringResult flat = run_filtering_experiment(
      pyramid_of(std::vector<float>(n * n, 0.5f), n, 1.0), small_options());
  for (RoughnessFilter f : measurable_filters()) {
    if (f == RoughnessFilter::kLean2010) continue;  // a Beckmann lobe, not the base GGX
    // Toksvig reads the mean normal's length, stored as float: 1 - |n| ~ 1e-7
    // at one texel, which a sharp lobe turns into ~1e-5 of profile error.
    const double tol = f == RoughnessFilter::kToksvig2005 ? 1e-4 : 1e-12;
    for (double alpha : {0.05, 0.3}) {
      const FilteringCell& c = cell(bumpy, f, alpha, 0);
      if (f == RoughnessFilter::kTokuyoshi2021)  // reads the normal's change between pixels
        EXPECT_GT(c.profile_error.mean, 1e-3);
      else
        EXPECT_NEAR(c.profile_error.mean, 0.0, tol) << roughness_filter_info(f).id;
      for (int level = 0; level <= 4; ++level)
        EXPECT_NEAR(cell(flat, f, alpha, level).profile_error.mean, 0.0, 1e-12)
            << roughness_filter_info(f).id << " level " << level;
    }
  }
}

// Schilling: "filtering bump maps in the common way ... results in a
// smoothened surface": the mean normal alone narrows the highlight, and
// widening the lobe from the roughness pyramid brings the width back.
TEST(Filtering, MipMappingAloneNarrowsTheHighlightAndTheVarianceRestoresIt) {
  const int n = 64;
  FilteringOptions o = small_options();
  o.footprints = 24;
  const FilteringResult r = run_filtering_experiment(pyramid_of(bumpy_heights(n, 2), n, 2.0), o);
  const FilteringCell& mip = cell(r, RoughnessFilter::kMipOnly, 0.05, 4);
  const FilteringCell& ggx = cell(r, RoughnessFilter::kGgxVarianceEstevez2019, 0.05, 4);
  EXPECT_LT(mip.width_ratio.interval.high, 0.5) << mip.width_ratio.mean;
  EXPECT_LT(std::abs(std::log(ggx.width_ratio.mean)), std::abs(std::log(mip.width_ratio.mean)));
  EXPECT_LT(ggx.profile_error.interval.high, mip.profile_error.interval.low);
  ASSERT_FALSE(r.claim.empty());
  ASSERT_EQ(r.summary.size(), measurable_filters().size());
  EXPECT_LE(r.summary[0].profile_error.mean, r.summary[1].profile_error.mean);
  EXPECT_EQ(filtering_findings(r).size(), 4u);
}

// "A number must not move when the camera moves half a pixel": with the
// pixel grid shifted by half a pixel and the filters reading the exact
// moments of each footprint, each filter's summary profile error and width
// ratio differ by less than the sum of the two intervals' widths (two
// estimates of one mean from different footprints: about 4 standard
// errors). The trilinear lookup does not pass this (README: its kernel is
// wider than the footprint), so it is the test's subject only aligned,
// where a level's texel is the footprint and both lookups must agree.
TEST(Filtering, HalfAPixelShiftKeepsTheSummaryWithExactFootprintMoments) {
  const int n = 64;
  const auto pyramid = pyramid_of(bumpy_heights(n, 5), n, 2.0);
  FilteringOptions o = small_options();
  o.footprints = 24;
  const FilteringResult aligned = run_filtering_experiment(pyramid, o);
  o.shift = 0.5;
  const FilteringResult half = run_filtering_experiment(pyramid, o);
  o.shift = 0.0;
  o.random_shift = true;  // each footprint anywhere on the texel grid
  const FilteringResult random = run_filtering_experiment(pyramid, o);
  o.random_shift = false;
  for (const FilteringResult* shifted : {&half, &random})
    for (const FilterSummary& a : aligned.summary)
      for (const FilterSummary& b : shifted->summary) {
        if (a.filter != b.filter) continue;
        const auto close = [](const MeanWithInterval& x, const MeanWithInterval& y) {
          const double spread =
              (x.interval.high - x.interval.low) + (y.interval.high - y.interval.low);
          return std::abs(x.mean - y.mean) <= spread;
        };
        EXPECT_TRUE(close(a.profile_error, b.profile_error))
            << roughness_filter_info(a.filter).id << ": " << a.profile_error.mean << " vs "
            << b.profile_error.mean;
        EXPECT_TRUE(close(a.width_ratio, b.width_ratio)) << roughness_filter_info(a.filter).id;
      }
  o.shift = 0.0;
  o.lookup = FilteringOptions::Lookup::kTrilinear;
  const FilteringResult trilinear = run_filtering_experiment(pyramid, o);
  for (std::size_t i = 0; i < aligned.summary.size(); ++i) {
    ASSERT_EQ(aligned.summary[i].filter, trilinear.summary[i].filter);
    // float storage of the pyramid against double sums: ~1e-7 relative
    EXPECT_NEAR(aligned.summary[i].profile_error.mean, trilinear.summary[i].profile_error.mean,
                1e-4 * aligned.summary[i].profile_error.mean)
        << roughness_filter_info(aligned.summary[i].filter).id;
  }
}

TEST(Filtering, SameBitsWhateverTheThreadCount) {
  const int n = 32;
  const auto pyramid = pyramid_of(bumpy_heights(n, 3), n, 1.0);
  FilteringOptions one = small_options(), two = small_options();
  one.jobs = 1;
  two.jobs = 2;
  EXPECT_EQ(filtering_json(run_filtering_experiment(pyramid, one), one, {}),
            filtering_json(run_filtering_experiment(pyramid, two), two, {}));
}

class FilteringCli : public TempDirTest {};

TEST_F(FilteringCli, WritesJsonAndCsvAndRefusesBadOptionsBeforeWriting) {
  Image image;
  image.width = image.height = 32;
  image.channels = {"Y"};
  const std::vector<float> heights = bumpy_heights(32, 4);
  image.pixels.assign(heights.begin(), heights.end());
  write_exr(image, path("h.exr"));
  const CliResult r =
      run_penumbra({"filtering", path("h.exr"), "-o", path("out"), "--texel-size", "1", "--alpha",
                    "0.1", "--max-level", "3", "--footprints", "4", "--sweep-step", "2"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("The chapter's claim"), std::string::npos) << r.out;
  std::ifstream in(path("out/filtering.json"));
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc["cells"].size(), measurable_filters().size() * 4);
  EXPECT_TRUE(doc["compared_against"].is_string());
  EXPECT_TRUE(std::filesystem::exists(path("out/filtering.csv")));

  for (const std::vector<std::string>& bad : {std::vector<std::string>{"--filter", "schilling1997"},
                                              {"--filter", "nope"},
                                              {"--alpha", "0"},
                                              {"--edge", "mirror"}}) {
    std::vector<std::string> args = {"filtering", path("h.exr"), "-o", path("bad")};
    args.insert(args.end(), bad.begin(), bad.end());
    const CliResult b = run_penumbra(args);
    EXPECT_EQ(b.code, 2) << bad[1] << ": " << b.err;
    EXPECT_FALSE(std::filesystem::exists(path("bad"))) << bad[1];
  }
  EXPECT_EQ(run_penumbra({"filtering", path("missing.exr"), "-o", path("bad")}).code, 2);
  EXPECT_FALSE(std::filesystem::exists(path("bad")));
}

}  // namespace
}  // namespace penumbra
