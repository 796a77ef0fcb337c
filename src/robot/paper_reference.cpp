// Values transcribed from the paper; data/paper/*.csv hold the same numbers and a test keeps the two
// in step.
#include "errfield/robot/paper_reference.hpp"

namespace errfield::robot::paper {

namespace {

constexpr VariogramRow kTable3[] = {
    {0, 10, 0.0047},  {10, 20, 0.0215}, {20, 30, 0.0528}, {30, 40, 0.1105},  {40, 50, 0.1992},  {50, 60, 0.3041},
    {60, 70, 0.4051}, {70, 80, 0.5048}, {80, 90, 0.6215}, {90, 100, 0.7023}, {100, 110, 0.7824},
};

constexpr VariogramRow kTable4[] = {
    {0, 200, 0.0154},     {200, 400, 0.0359},   {400, 600, 0.0791},   {600, 800, 0.1410},
    {800, 1000, 0.2234},  {1000, 1200, 0.3283}, {1200, 1400, 0.4633}, {1400, 1600, 0.6238},
    {1600, 1800, 0.8293}, {1800, 2000, 1.0138}, {2000, 2200, 1.0710},
};

constexpr ErrorSummaryRow kTable6[] = {
    {"none", 1.346, 0.514, 0.321},
    {"kinematic", 0.313, 0.109, 0.062},
    {"position-idw", 0.206, 0.088, 0.041},
    {"distance-idw", 0.104, 0.037, 0.029},
};

constexpr ErrorSummaryRow kTable8[] = {
    {"before", 1.609, 1.108, 0.274},
    {"after", 0.150, 0.052, 0.041},
};

}  // namespace

std::span<const VariogramRow> table3_joint_variogram() { return kTable3; }
std::span<const VariogramRow> table4_task_variogram() { return kTable4; }
std::span<const ErrorSummaryRow> table6_compensation() { return kTable6; }
std::span<const ErrorSummaryRow> table8_assembly() { return kTable8; }

std::array<std::array<double, 2>, 6> table2_joint_ranges_deg() {
  return {{{45, 90}, {-90, 60}, {40, 80}, {15, 30}, {15, 30}, {15, 30}}};
}

}  // namespace errfield::robot::paper
