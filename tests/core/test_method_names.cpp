// The listing names of the method enumerations (core/method_names.h): every
// value has one, and no two values share it.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "core/method_names.h"

namespace penumbra {
namespace {

template <typename Enum, std::size_t N>
void expect_named_once(const EnumName<Enum> (&table)[N], std::initializer_list<Enum> values) {
  std::set<std::string> names;
  for (Enum value : values) {
    const std::string name = name_of<Enum>(table, value);
    EXPECT_NE(name, "?");
    EXPECT_TRUE(names.insert(name).second) << name;
  }
  EXPECT_EQ(names.size(), N);
}

TEST(MethodNames, EveryValueOfTheMethodTablesHasOneName) {
  for (const MethodInfo& m : all_methods()) {
    EXPECT_STRNE(name_of<MethodKind>(kMethodKindNames, m.kind), "?") << m.id;
    EXPECT_STRNE(name_of<FactorLobes>(kFactorLobesNames, m.lobes), "?") << m.id;
    EXPECT_STRNE(name_of<FactorLobes>(kFactorLobesPhrases, m.lobes), "?") << m.id;
  }
  expect_named_once(kMethodKindNames, {MethodKind::kFactor, MethodKind::kFactorAndAdjustment,
                                       MethodKind::kAdjustment, MethodKind::kMicrofacet});
  expect_named_once(kFactorLobesNames,
                    {FactorLobes::kScene, FactorLobes::kDiffuse, FactorLobes::kAll});
  expect_named_once(kFactorLobesPhrases,
                    {FactorLobes::kScene, FactorLobes::kDiffuse, FactorLobes::kAll});
  for (const RoughnessFilterInfo& f : all_roughness_filters())
    EXPECT_STRNE(name_of<FilteredDistribution>(kFilteredDistributionNames, f.distribution), "?")
        << f.id;
  expect_named_once(kFilteredDistributionNames,
                    {FilteredDistribution::kGgx, FilteredDistribution::kBeckmann,
                     FilteredDistribution::kSchillingBlinnPhong});
}

}  // namespace
}  // namespace penumbra
