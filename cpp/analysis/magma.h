// The magma colour map (van der Walt and Smith, 2015), which the FLIP papers
// show their error maps in: 0 black, through purple and orange, 1 pale
// yellow, perceptually uniform and readable in grey.
#pragma once

#include <array>
#include <vector>

namespace penumbra {

// The 8-bit sRGB colour of `value` in [0, 1] (clamped; NaN is 0): entry
// round(255 value) of the 256-entry map, as FLIP's tools quantise it.
std::array<unsigned char, 3> magma_rgb8(double value);

// Every value of `values` so, three bytes each (for write_png_rgb8).
std::vector<unsigned char> magma_rgb8(const std::vector<float>& values);

}  // namespace penumbra
