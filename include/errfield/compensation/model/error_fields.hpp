#pragma once
/// The error fields a CompensationModel can carry (compensation.hpp), built from measurements.
/// Use the distance-IDW field for the paper's method, the position-IDW field for the classic
/// 8-vertex IDW of registered position errors. Kriging fields live in kriging_fields.hpp.
///
/// Every field refuses targets outside the region it was built on (inside_region = false): an
/// interpolation model says nothing reliable beyond its samples.

#include <memory>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include "errfield/grid_idw.hpp"
#include "errfield/regular_grid.hpp"
#include "errfield/compensation/model/compensation.hpp"

namespace errfield::compensation {

/// The paper's field (SPEC eqs. 19–23): distance errors dL_j of the grid nodes to a base point P0,
/// interpolated by 8-vertex IDW (power p, 1 in the paper) to the target's nominal position, then
/// projected along m = (P − P0)/|P − P0|. Only the radial component is predicted. Targets within
/// 1 mm of P0 (direction undefined) are refused like targets outside the grid.
/// `node_distance_error_mm` is in the grid's node order (RegularGrid3::node_index).
std::shared_ptr<const ErrorField> make_distance_idw_field(const RegularGrid3& grid,
                                                          std::vector<double> node_distance_error_mm,
                                                          const Eigen::Vector3d& base_point_mm,
                                                          const GridIdwOptions& options = {});

/// 8-vertex IDW of 3-D position errors dP_j (robot frame, mm) of the grid nodes.
std::shared_ptr<const ErrorField> make_position_idw_field(const RegularGrid3& grid,
                                                          std::vector<Eigen::Vector3d> node_position_error_mm,
                                                          const GridIdwOptions& options = {});

/// Reads a field from its JSON form (the "field" member of a model file); null → nullptr.
/// Throws InputError naming `source` and the member for anything malformed.
std::shared_ptr<const ErrorField> error_field_from_json(const nlohmann::json& j, const std::string& source);

/// Errors the model's field was fitted on, one row per sample (1 or 3 columns); empty without a field.
Eigen::MatrixXd fitted_errors(const ErrorField& field);

}  // namespace errfield::compensation
