#include "errfield/interpolation_options.hpp"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "errfield/error.hpp"

namespace errfield {
namespace interpolation_options_test {

std::string message_of(const KrigingOptionText& t, const OptionNames& n = {}) {
  try {
    (void)kriging_options_from_text(t, n);
  } catch (const ArgumentError& e) {
    return e.what();
  }
  return "";
}

TEST(KrigingOptionsFromText, DefaultsAreOrdinaryDenseMicroscale) {
  const KrigingOptions o = kriging_options_from_text({});
  EXPECT_EQ(o.kind, KrigingKind::Ordinary);
  EXPECT_EQ(o.backend, KrigingBackend::Dense);
  EXPECT_EQ(o.nugget, NuggetTreatment::MicroScale);
  EXPECT_EQ(o.duplicates, DuplicatePolicy::Error);
}

TEST(KrigingOptionsFromText, ANeighbourhoodAloneSelectsTheLocalBackEnd) {
  KrigingOptionText t;
  t.neighbors = 12;
  KrigingOptions o = kriging_options_from_text(t);
  EXPECT_EQ(o.backend, KrigingBackend::Local);
  EXPECT_EQ(o.neighbors, 12u);
  EXPECT_TRUE(std::isinf(o.radius));
  t = {};
  t.radius = 40.0;
  o = kriging_options_from_text(t);
  EXPECT_EQ(o.backend, KrigingBackend::Local);
  EXPECT_EQ(o.neighbors, 0u);
  EXPECT_EQ(o.radius, 40.0);
}

TEST(KrigingOptionsFromText, KindWordsAndDriftOrders) {
  KrigingOptionText t;
  t.kind = "universal2";
  EXPECT_EQ(kriging_options_from_text(t).drift_order, 2);
  t.kind = "universal";
  EXPECT_EQ(kriging_options_from_text(t).drift_order, 1);
  t.drift_order = 0;
  EXPECT_EQ(kriging_options_from_text(t).drift_order, 0);
  t.kind = "universal1";
  t.drift_order = 2;
  EXPECT_NE(message_of(t).find("contradicts kind universal1"), std::string::npos) << message_of(t);
  t = {};
  t.kind = "simple";
  t.mean = std::vector<double>{0.5, 1.5};
  const KrigingOptions o = kriging_options_from_text(t);
  EXPECT_EQ(o.kind, KrigingKind::Simple);
  EXPECT_EQ(o.simple_mean, (std::vector<double>{0.5, 1.5}));
}

TEST(KrigingOptionsFromText, RefusalsNameTheOptionAsTheCallerSpellsIt) {
  OptionNames cli;
  cli.kind = "--kind";
  cli.mean = "--mean";
  cli.backend = "--backend";
  cli.neighbors = "--neighbors";
  cli.radius = "--radius";
  cli.nugget = "--nugget-as";
  KrigingOptionText t;
  t.kind = "kriged";
  EXPECT_EQ(message_of(t, cli).rfind("--kind is 'kriged'; expected simple, ordinary", 0), 0u) << message_of(t, cli);
  EXPECT_EQ(message_of(t).rfind("kind is 'kriged'", 0), 0u);
  t = {};
  t.kind = "simple";
  EXPECT_NE(message_of(t, cli).find("--kind simple needs the known mean (--mean)"), std::string::npos);
  t.mean = std::vector<double>{NAN};
  EXPECT_NE(message_of(t, cli).find("--mean is nan"), std::string::npos) << message_of(t, cli);
  t = {};
  t.mean = std::vector<double>{1.0};
  EXPECT_NE(message_of(t, cli).find("--mean applies to --kind simple only"), std::string::npos);
  t = {};
  t.backend = "dense";
  t.neighbors = 5;
  EXPECT_NE(message_of(t, cli).find("--neighbors/--radius select the neighbourhood of --backend local, not --backend dense"),
            std::string::npos)
      << message_of(t, cli);
  t = {};
  t.backend = "local";
  EXPECT_NE(message_of(t, cli).find("--backend local needs --neighbors K and/or --radius R"), std::string::npos);
  t = {};
  t.nugget = "both";
  EXPECT_NE(message_of(t, cli).find("--nugget-as is 'both'; expected micro or error"), std::string::npos);
  t = {};
  t.radius = -1.0;
  EXPECT_NE(message_of(t, cli).find("--radius is -1; expected a value > 0"), std::string::npos) << message_of(t, cli);
}

TEST(ScatteredIdwOptionsFromText, DefaultsAndRefusals) {
  const ScatteredIdwOptions d = scattered_idw_options_from_text({});
  EXPECT_EQ(d.power, 2.0);  // gstat's idw
  EXPECT_EQ(d.neighbors, 0u);
  EXPECT_TRUE(std::isinf(d.radius));
  const ScatteredIdwOptions o = scattered_idw_options_from_text({1.0, 8, 100.0});
  EXPECT_EQ(o.power, 1.0);
  EXPECT_EQ(o.neighbors, 8u);
  EXPECT_EQ(o.radius, 100.0);
  OptionNames cli;
  cli.power = "--power";
  try {
    (void)scattered_idw_options_from_text({-1.0, {}, {}}, cli);
    FAIL() << "a negative power was accepted";
  } catch (const ArgumentError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--power is -1; expected a finite value >= 0", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace errfield
