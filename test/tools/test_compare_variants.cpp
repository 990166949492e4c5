// compare's rows: the published rules keep their own kernel amplitude whatever the default's
// reliability discount, and a row's overrides still apply on top.
#include <gtest/gtest.h>

#include <stdexcept>

#include "compare_variants.h"

namespace eo = evidential_octomap;
using eo::tools::variantConfig;

TEST(CompareVariants, PublishedRulesUseTheirOwnKernel) {
  eo::SemanticConfig base;
  base.sigma0 = 0.4;
  base.other_class_weight = 0.3;
  for (const char* name : {"sbki", "ebs", "reference_compat"}) {
    EXPECT_EQ(variantConfig(name, base).sigma0, 1.0) << name;
    EXPECT_EQ(variantConfig(name, base).other_class_weight, 1.0) << name;
  }
  for (const char* name : {"dempster", "dempster-paper"}) {
    EXPECT_EQ(variantConfig(name, base).sigma0, 0.4) << name;
    EXPECT_EQ(variantConfig(name, base).other_class_weight, 0.3) << name;
  }
}

TEST(CompareVariants, OverridesApplyAfterTheNamedVariant) {
  const eo::SemanticConfig c = variantConfig("ebs:sigma0=0.5:length_scale=0.25", {});
  EXPECT_EQ(c.rule, "ebs");
  EXPECT_EQ(c.sigma0, 0.5);
  EXPECT_EQ(c.length_scale, 0.25);
  EXPECT_THROW(variantConfig("ebs:sigma0=-1", {}), std::invalid_argument);
  EXPECT_THROW(variantConfig("nonsense", {}), std::invalid_argument);
}
