#include "errfield/coregionalization_model.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"

namespace errfield {
namespace coregionalization_model_test {

Eigen::MatrixXd two_by_two(double a, double b, double c) {
  Eigen::MatrixXd m(2, 2);
  m << a, b, b, c;
  return m;
}

CoregionalizationModel nugget_plus_spherical() {
  return CoregionalizationModel({{.kind = ModelKind::Nugget, .range = 0.0, .nu = 0.5, .sills = two_by_two(0.1, 0.02, 0.2)},
                                 {.kind = ModelKind::Spherical, .range = 100.0, .nu = 0.5, .sills = two_by_two(1.0, -0.6, 0.5)}},
                                {}, {"a", "b"});
}

TEST(CoregionalizationModel, DirectAndCrossVariogramsAreTheSumsOfTheStructures) {
  const CoregionalizationModel m = nugget_plus_spherical();
  EXPECT_EQ(m.components(), 2);
  // Closed form of the spherical structure at h = 50: 1.5 * 0.5 - 0.5 * 0.125.
  const double sph50 = 0.6875;
  EXPECT_DOUBLE_EQ(m.gamma(0, 0, 50.0), 0.1 + 1.0 * sph50);
  EXPECT_DOUBLE_EQ(m.gamma(0, 1, 50.0), 0.02 - 0.6 * sph50);
  EXPECT_DOUBLE_EQ(m.gamma(1, 0, 50.0), m.gamma(0, 1, 50.0));
  EXPECT_EQ(m.gamma(1, 1, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(m.gamma(1, 1, 500.0), 0.7);
  const Eigen::MatrixXd c = m.covariance_matrix(50.0);
  EXPECT_DOUBLE_EQ(c(0, 1), -0.6 * (1.0 - sph50));
  EXPECT_TRUE(m.sill().isApprox(two_by_two(1.1, -0.58, 0.7)));
  EXPECT_TRUE(m.nugget().isApprox(two_by_two(0.1, 0.02, 0.2)));
  EXPECT_EQ(m.direct_model(1).to_string(), VariogramModel::parse("nug(0.2)+sph(sill=0.5,range=100)").to_string());
}

TEST(CoregionalizationModel, IntrinsicModelScalesTheSharedVariogram) {
  const VariogramModel shared = VariogramModel::parse("exp(sill=2,range=30)+nug(0.5)");
  const CoregionalizationModel m = CoregionalizationModel::intrinsic(shared, two_by_two(1.0, 0.5, 1.0));
  for (double h : {0.0, 1.0, 30.0, 200.0}) {
    EXPECT_DOUBLE_EQ(m.gamma(0, 0, h), shared.gamma(h));
    EXPECT_NEAR(m.gamma(0, 1, h), 0.5 * shared.gamma(h), 1e-15);
  }
}

TEST(CoregionalizationModel, RefusesMatricesThatAreNotPositiveSemiDefiniteOrNotSymmetric) {
  // |cross sill| > sqrt(product of direct sills): the cokriging variance could be negative.
  EXPECT_THROW(CoregionalizationModel({{.kind = ModelKind::Spherical, .range = 10.0, .nu = 0.5,
                                        .sills = two_by_two(1.0, 1.2, 1.0)}}),
               ArgumentError);
  Eigen::MatrixXd asym = two_by_two(1.0, 0.2, 1.0);
  asym(1, 0) = 0.3;
  EXPECT_THROW(CoregionalizationModel({{.kind = ModelKind::Spherical, .range = 10.0, .nu = 0.5, .sills = asym}}),
               ArgumentError);
  EXPECT_THROW(CoregionalizationModel({{.kind = ModelKind::Linear, .range = 0.0, .nu = 0.5, .sills = two_by_two(1, 0, 1)}}),
               ArgumentError);
  EXPECT_THROW(CoregionalizationModel({{.kind = ModelKind::Spherical, .range = -1.0, .nu = 0.5, .sills = two_by_two(1, 0, 1)}}),
               ArgumentError);
  EXPECT_THROW(CoregionalizationModel({{.kind = ModelKind::Nugget, .range = 0.0, .nu = 0.5, .sills = two_by_two(1, 0, 1)},
                                       {.kind = ModelKind::Spherical, .range = 5.0, .nu = 0.5, .sills = Eigen::MatrixXd::Identity(3, 3)}}),
               ArgumentError);
  EXPECT_THROW(CoregionalizationModel(std::vector<CoregionalizationStructure>{}), ArgumentError);
  // A semi-definite matrix (perfectly correlated components) is valid.
  EXPECT_NO_THROW(CoregionalizationModel({{.kind = ModelKind::Gaussian, .range = 5.0, .nu = 0.5, .sills = two_by_two(1.0, 2.0, 4.0)}}));
}

TEST(CoregionalizationModel, JsonRoundTripKeepsEveryNumberAndTheAnisotropy) {
  const CoregionalizationModel m(
      {{.kind = ModelKind::Matern, .range = 40.0, .nu = 1.5, .sills = two_by_two(0.3, 0.1, 0.2)}},
      Anisotropy::ard({1.0, 0.5}), {"ex", "ey"});
  const nlohmann::json j = m;
  EXPECT_TRUE(is_coregionalization_json(j));
  const auto back = j.get<CoregionalizationModel>();
  EXPECT_EQ(back.component_names(), m.component_names());
  EXPECT_EQ(back.structures()[0].nu, 1.5);
  EXPECT_EQ(back.structures()[0].sills, m.structures()[0].sills);
  EXPECT_EQ(back.anisotropy().to_string(), m.anisotropy().to_string());
  nlohmann::json bad = j;
  bad["structures"][0]["sills"][1] = {0.1};
  EXPECT_THROW((void)bad.get<CoregionalizationModel>(), ArgumentError);
  EXPECT_FALSE(is_coregionalization_json(nlohmann::json::parse(R"({"components":[{"kind":"nug","sill":1}]})")));
}

TEST(CoregionalizationModel, LoadingAFileNamesItWhenTheModelIsBad) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "errfield_lmc_load_test";
  std::filesystem::create_directories(dir);
  const std::filesystem::path good = dir / "good.json", bad = dir / "bad.json";
  nlohmann::json j = nugget_plus_spherical();
  std::ofstream(good) << j.dump();
  EXPECT_EQ(load_coregionalization_model(good.string()).to_string(), nugget_plus_spherical().to_string());
  j["structures"][1]["sills"] = {{1.0, 2.0}, {2.0, 1.0}};  // eigenvalue -1: not PSD
  std::ofstream(bad) << j.dump();
  try {
    (void)load_coregionalization_model(bad.string());
    ADD_FAILURE() << "a non-PSD LMC was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("positive semi-definite"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace coregionalization_model_test
}  // namespace errfield
