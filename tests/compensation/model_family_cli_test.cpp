// `fit --model FAMILY` (issue 19 friction): a variogram family whose parameters fit estimates
// (`--model mat`, `mat(2.5)@iso`, `gau@ard`), on SIMULATED KR16 data with scattered joints.

#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/variogram_model.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace model_family_cli_test {

class ModelFamily : public testing::CliTest {
 protected:
  void SetUp() override {
    const auto r = run("simulate --robot kr16 --seed 12 --sample scattered:70 --joint-box "
                       "-60,60,-100,-40,20,110,-90,90,30,100,-90,90 --measure positions --robot-out r.json --out d.csv");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  /// The field's variogram model of a model file.
  VariogramModel field_model(const std::string& file) {
    return VariogramModel::parse(nlohmann::json::parse(read(file))["field"]["model"].get<std::string>());
  }
};

TEST_F(ModelFamily, TheFamilyIsKeptAndItsParametersEstimated) {
  for (const std::string space : {"joint", "task"}) {
    SCOPED_TRACE(space);
    const auto r = run("fit --robot r.json --data d.csv --method kinematic+kriging --space " + space +
                       " --model mat --out m.json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const VariogramModel m = field_model("m.json");
    bool matern = false;
    for (const auto& c : m.components()) {
      EXPECT_TRUE(c.kind == ModelKind::Matern || c.kind == ModelKind::Nugget) << m.to_string();
      if (c.kind == ModelKind::Matern) {
        matern = true;
        EXPECT_TRUE(c.nu == 1.5 || c.nu == 2.5) << m.to_string();
        EXPECT_GT(c.sill, 0.0);
        EXPECT_GT(c.range, 0.0);
      }
    }
    EXPECT_TRUE(matern) << m.to_string();
  }
  // A fixed smoothness and isotropy; ARD only.
  ASSERT_EQ(run("fit --robot r.json --data d.csv --model \"mat(2.5)@iso\" --out iso.json").exit_code, 0);
  const VariogramModel iso = field_model("iso.json");
  EXPECT_TRUE(iso.anisotropy().isotropic()) << iso.to_string();
  for (const auto& c : iso.components())
    if (c.kind == ModelKind::Matern) {
      EXPECT_EQ(c.nu, 2.5);
    }
  ASSERT_EQ(run("fit --robot r.json --data d.csv --model gau@ard --out ard.json").exit_code, 0);
  const VariogramModel ard = field_model("ard.json");
  EXPECT_EQ(ard.anisotropy().type(), Anisotropy::Type::Ard) << ard.to_string();
  for (const auto& c : ard.components()) EXPECT_TRUE(c.kind == ModelKind::Gaussian || c.kind == ModelKind::Nugget);
  // A model given in full is used as given.
  ASSERT_EQ(run("fit --robot r.json --data d.csv --model \"mat(sill=0.05,range=80,nu=1.5)+nug(0.001)\" --out full.json")
                .exit_code,
            0);
  EXPECT_EQ(field_model("full.json").to_string(), VariogramModel::parse("mat(sill=0.05,range=80,nu=1.5)+nug(0.001)").to_string());
}

TEST_F(ModelFamily, FamiliesThatCannotBeEstimatedAreNamed) {
  for (const std::string bad : {"pow", "lin", "nug", "\"mat(0)\"", "\"gau(2)\""}) {
    const auto r = run("fit --robot r.json --data d.csv --model " + bad + " --out m.json");
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find("--model"), std::string::npos) << r.err;
  }
}

}  // namespace model_family_cli_test
}  // namespace errfield
