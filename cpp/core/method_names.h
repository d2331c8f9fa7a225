// The names that describe the methods in listings (`penumbra methods`, its
// JSON, the docs): one table per enumeration of the method tables
// (terminator.h, roughness_filter.h), read with name_of().
//
// They live here rather than beside their enumerations because terminator.h
// and roughness_filter.h are inputs of the evaluator's code digest
// (CMakeLists.txt, _pixel_common): a wording change there would re-render
// every cached render.
#pragma once

#include "core/enum_names.h"
#include "core/roughness_filter.h"
#include "core/terminator.h"

namespace penumbra {

// The "family" of `penumbra methods --json`.
inline constexpr EnumName<MethodKind> kMethodKindNames[] = {
    {"factor", MethodKind::kFactor},
    {"factor+adjustment", MethodKind::kFactorAndAdjustment},
    {"adjustment", MethodKind::kAdjustment},
    {"microfacet", MethodKind::kMicrofacet}};

// The "factor_lobes" of `penumbra methods --json`.
inline constexpr EnumName<FactorLobes> kFactorLobesNames[] = {
    {"scene", FactorLobes::kScene}, {"diffuse", FactorLobes::kDiffuse}, {"all", FactorLobes::kAll}};

// The lobes a factor scales, in words (the text listing).
inline constexpr EnumName<FactorLobes> kFactorLobesPhrases[] = {
    {"the lobes of /terminator/lobes", FactorLobes::kScene},
    {"the diffuse lobe", FactorLobes::kDiffuse},
    {"every lobe", FactorLobes::kAll}};

// The lobe shape a roughness filter hands to shading.
inline constexpr EnumName<FilteredDistribution> kFilteredDistributionNames[] = {
    {"ggx", FilteredDistribution::kGgx},
    {"beckmann", FilteredDistribution::kBeckmann},
    {"schilling-blinn-phong", FilteredDistribution::kSchillingBlinnPhong}};

}  // namespace penumbra
