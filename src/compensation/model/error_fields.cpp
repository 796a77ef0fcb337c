#include "errfield/compensation/model/error_fields.hpp"

#include <limits>

#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/compensation/model/kriging_fields.hpp"

namespace errfield::compensation {

using namespace errfield::robot;

namespace {

nlohmann::json grid_to_json(const RegularGrid3& g) {
  return {{"origin_mm", {g.origin().x(), g.origin().y(), g.origin().z()}},
          {"step_mm", {g.step().x(), g.step().y(), g.step().z()}},
          {"counts", {g.counts()[0], g.counts()[1], g.counts()[2]}}};
}

[[noreturn]] void bad(const std::string& source, const std::string& what) {
  throw InputError(source + ": " + what, source);
}

Eigen::Vector3d vec3(const nlohmann::json& j, const std::string& source, const std::string& name) {
  if (!j.is_array() || j.size() != 3) bad(source, "member \"" + name + "\": expected an array of 3 numbers");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number()) bad(source, "member \"" + name + "\"[" + std::to_string(i) + "]: expected a number");
    v[i] = j[i].get<double>();
    if (!std::isfinite(v[i])) bad(source, "member \"" + name + "\"[" + std::to_string(i) + "]: not finite");
  }
  return v;
}

const nlohmann::json& member(const nlohmann::json& j, const std::string& source, const std::string& name) {
  if (!j.contains(name)) bad(source, "member \"" + name + "\" is missing");
  return j[name];
}

RegularGrid3 grid_from_json(const nlohmann::json& j, const std::string& source) {
  const auto& counts = member(j, source, "counts");
  if (!counts.is_array() || counts.size() != 3) bad(source, "member \"grid.counts\": expected 3 integers");
  std::array<int, 3> c{};
  for (int i = 0; i < 3; ++i) {
    // Range-checked as read: get<int>() keeps the low 32 bits (4294967298 would be read as 2).
    const auto n = json_integer_in(counts[i], 0, std::numeric_limits<int>::max());
    if (!n) bad(source, "member \"grid.counts\"[" + std::to_string(i) + "]: expected an integer from 0 to " +
                        std::to_string(std::numeric_limits<int>::max()) + ", got " + counts[i].dump());
    c[i] = static_cast<int>(*n);
  }
  try {
    return RegularGrid3(vec3(member(j, source, "origin_mm"), source, "grid.origin_mm"),
                        vec3(member(j, source, "step_mm"), source, "grid.step_mm"), c);
  } catch (const ArgumentError& e) {
    bad(source, std::string("member \"grid\": ") + e.what());
  }
}

GridIdwOptions idw_options(double power) {
  GridIdwOptions o;
  o.power = power;
  o.threads = 1;  // one target at a time here; callers parallelize over targets
  return o;
}

/// Targets on a face of the grid come from FK of rounded joints or from IK: micrometres outside
/// must count as inside (kRegionToleranceMm), and the IDW must then treat them as on the face.
GridIdwOptions with_face_tolerance(GridIdwOptions o, const RegularGrid3& grid) {
  o.boundary_tolerance = std::min(0.01, std::max(o.boundary_tolerance, kRegionToleranceMm / grid.step().minCoeff()));
  return o;
}

bool in_grid(const RegularGrid3& grid, const Eigen::Vector3d& p) { return grid.contains(p, kRegionToleranceMm); }

class DistanceIdwField final : public ErrorField {
 public:
  DistanceIdwField(const RegularGrid3& grid, std::vector<double> values, const Eigen::Vector3d& base,
                   const GridIdwOptions& options)
      : grid_(grid), values_(std::move(values)), base_(base), options_(with_face_tolerance(options, grid)),
        idw_(grid_, std::span<const double>(values_), options_) {}
  ErrorPrediction predict(const Eigen::Vector3d& p, const JointVector&) const override {
    ErrorPrediction out;
    if (!in_grid(grid_, p)) {
      out.inside_region = false;
      return out;
    }
    // Within 1 mm of the base point the direction m of eq. 22 is undefined: refuse.
    if ((p - base_).norm() < 1.0) {
      out.inside_region = false;
      return out;
    }
    out.distance_error_mm = idw_(p);
    out.position_error_mm = out.distance_error_mm * radial_direction(p, base_);
    return out;
  }
  nlohmann::json to_json() const override {
    return {{"kind", "distance-idw"}, {"grid", grid_to_json(grid_)}, {"power", options_.power},
            {"base_point_mm", {base_.x(), base_.y(), base_.z()}}, {"node_distance_error_mm", values_}};
  }
  std::string describe() const override {
    return "distance-error IDW (power " + std::to_string(options_.power) + ") on grid " + grid_.describe();
  }

 private:
  RegularGrid3 grid_;
  std::vector<double> values_;
  Eigen::Vector3d base_;
  GridIdwOptions options_;
  GridIdw<double> idw_;
};

class PositionIdwField final : public ErrorField {
 public:
  PositionIdwField(const RegularGrid3& grid, std::vector<Eigen::Vector3d> values, const GridIdwOptions& options)
      : grid_(grid), values_(std::move(values)), options_(with_face_tolerance(options, grid)),
        idw_(grid_, std::span<const Eigen::Vector3d>(values_), options_) {}
  ErrorPrediction predict(const Eigen::Vector3d& p, const JointVector&) const override {
    ErrorPrediction out;
    if (!in_grid(grid_, p)) {
      out.inside_region = false;
      return out;
    }
    out.position_error_mm = idw_(p);
    return out;
  }
  nlohmann::json to_json() const override {
    nlohmann::json v = nlohmann::json::array();
    for (const auto& e : values_) v.push_back({e.x(), e.y(), e.z()});
    return {{"kind", "position-idw"}, {"grid", grid_to_json(grid_)}, {"power", options_.power},
            {"node_position_error_mm", v}};
  }
  std::string describe() const override {
    return "position-error IDW (power " + std::to_string(options_.power) + ") on grid " + grid_.describe();
  }

 private:
  RegularGrid3 grid_;
  std::vector<Eigen::Vector3d> values_;
  GridIdwOptions options_;
  GridIdw<Eigen::Vector3d> idw_;
};

}  // namespace

std::shared_ptr<const ErrorField> make_distance_idw_field(const RegularGrid3& grid, std::vector<double> node_dl,
                                                          const Eigen::Vector3d& base_point_mm,
                                                          const GridIdwOptions& options) {
  return std::make_shared<DistanceIdwField>(grid, std::move(node_dl), base_point_mm, options);
}

std::shared_ptr<const ErrorField> make_position_idw_field(const RegularGrid3& grid,
                                                          std::vector<Eigen::Vector3d> node_dp,
                                                          const GridIdwOptions& options) {
  return std::make_shared<PositionIdwField>(grid, std::move(node_dp), options);
}

std::shared_ptr<const ErrorField> error_field_from_json(const nlohmann::json& j, const std::string& source) {
  if (j.is_null()) return nullptr;
  if (!j.is_object()) bad(source, "member \"field\": expected an object or null");
  const auto& kind = member(j, source, "kind");
  if (!kind.is_string()) bad(source, "member \"field.kind\": expected a string");
  const std::string k = kind.get<std::string>();
  if (auto kriged = kriging_field_from_json(j, source)) return kriged;
  const auto& power = member(j, source, "power");
  if (!power.is_number()) bad(source, "member \"field.power\": expected a number");
  const RegularGrid3 grid = grid_from_json(member(j, source, "grid"), source);
  try {
    if (k == "distance-idw") {
      const auto& v = member(j, source, "node_distance_error_mm");
      if (!v.is_array() || v.size() != grid.node_count())
        bad(source, "member \"node_distance_error_mm\": expected " + std::to_string(grid.node_count()) + " numbers");
      std::vector<double> values;
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (!v[i].is_number()) bad(source, "member \"node_distance_error_mm\"[" + std::to_string(i) + "]: expected a number");
        values.push_back(v[i].get<double>());
      }
      return make_distance_idw_field(grid, std::move(values),
                                     vec3(member(j, source, "base_point_mm"), source, "base_point_mm"),
                                     idw_options(power.get<double>()));
    }
    if (k == "position-idw") {
      const auto& v = member(j, source, "node_position_error_mm");
      if (!v.is_array() || v.size() != grid.node_count())
        bad(source, "member \"node_position_error_mm\": expected " + std::to_string(grid.node_count()) + " [dx,dy,dz] triples");
      std::vector<Eigen::Vector3d> values;
      for (std::size_t i = 0; i < v.size(); ++i)
        values.push_back(vec3(v[i], source, "node_position_error_mm[" + std::to_string(i) + "]"));
      return make_position_idw_field(grid, std::move(values), idw_options(power.get<double>()));
    }
  } catch (const ArgumentError& e) {
    bad(source, std::string("member \"field\": ") + e.what());
  }
  bad(source, "member \"field.kind\": unknown kind '" + k + "' (expected distance-idw, position-idw, distance-kriging or vector-kriging)");
}

Eigen::MatrixXd fitted_errors(const ErrorField& field) {
  // Every field serializes the errors it interpolates; reading them back keeps the fields free of a
  // second accessor.
  const nlohmann::json j = field.to_json();
  const char* names[] = {"values", "node_distance_error_mm", "node_position_error_mm"};
  for (const char* name : names) {
    if (!j.contains(name) || !j[name].is_array() || j[name].empty()) continue;
    const auto& v = j[name];
    const bool vector = v[0].is_array();
    Eigen::MatrixXd e(static_cast<Eigen::Index>(v.size()), vector ? 3 : 1);
    for (std::size_t i = 0; i < v.size(); ++i)
      for (int c = 0; c < e.cols(); ++c)
        e(static_cast<Eigen::Index>(i), c) = vector ? v[i][static_cast<std::size_t>(c)].get<double>() : v[i].get<double>();
    return e;
  }
  return {};
}

}  // namespace errfield::compensation
