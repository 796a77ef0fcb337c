#pragma once
// Points for a GIS user: samples and targets read from a vector layer (GeoPackage, shapefile,
// GeoJSON, any format GDAL's OGR reads) as well as from a CSV, and predictions at points written
// as a GeoPackage. A layer is read into the same CsvTable a CSV gives, so every command treats
// both alike: the coordinates of each point geometry are the columns x, y (and z for 3-D points),
// followed by the layer's attribute fields (an attribute named x, y or z is replaced by the
// geometry's). The layer's CRS comes along (coordinate_system.hpp).

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cli/coordinate_system.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/row_labels.hpp"

namespace errfield::cli {

/// True when `path` names a vector file by its extension (.gpkg, .shp, .geojson, .json, .fgb,
/// .gml, .kml, .sqlite; case-insensitive); a CSV or anything else is read as CSV.
bool is_vector_path(const std::string& path);

/// The points of a CSV or of a vector layer.
struct PointTable {
  CsvTable table;
  /// For a vector layer "x", "y" (and "z"): the columns that hold the geometry; empty for a CSV.
  std::vector<std::string> geometry_columns;
  std::optional<Crs> crs;  ///< the layer's CRS; none for a CSV
  std::string layer;       ///< the layer's name; empty for a CSV
  std::vector<long long> feature_ids;  ///< each row's feature id (FID); empty for a CSV

  /// The coordinate columns: `coords_option` (comma-separated, as --coords) when given, else the
  /// geometry's columns; ArgumentError naming `option` when neither (a CSV needs --coords).
  std::vector<std::string> coordinate_columns(const std::string& coords_option, const std::string& option) const;
  /// Row labels for messages: "pts.gpkg layer 'pts' FID:7" for a layer, "pts.csv:7" for a CSV.
  RowLabels labels(std::string noun) const;
};

/// What a reader must find in every feature of a layer.
struct RequiredFields {
  std::vector<std::string> numeric;  ///< fields read as numbers (the --value attributes)
  bool allow_null = false;           ///< a null is a value not measured there (heterotopic data)
};

/// Reads `path` (named `option`, such as --samples, in messages): a vector layer when
/// is_vector_path, else a CSV (CsvTable::read). A layer must be the file's only layer and hold
/// points (2-D or 3-D, all alike); a geometry of another type, an empty or missing one, a field of
/// `required` that the layer lacks or that is null or not a number in a feature are refused with
/// an InputError naming the file, the layer, the feature (FID) and the field.
PointTable read_point_table(const std::string& path, const std::string& option, const RequiredFields& required = {});

/// One attribute of a GeoPackage written by encode_point_geopackage: numbers (NaN is null) or
/// text (an empty cell is null; a column whose cells are all integers is written as integers, all
/// numbers as reals, else as text).
struct PointField {
  std::string name;
  std::vector<double> numbers;
  std::vector<std::string> text;
  bool is_text = false;
};

/// The bytes of a GeoPackage with one point layer `layer`: a point at each row of `coords` (N x 2
/// or N x 3) with `fields` (each N values), in `crs` when given. Written in memory (GDAL's /vsimem)
/// for the caller to commit atomically.
std::string encode_point_geopackage(const std::string& layer, const Eigen::MatrixXd& coords,
                                    const std::vector<PointField>& fields, const std::optional<Crs>& crs);

/// The name of the layer written into `path`: its file name without directory and extension.
std::string layer_name_of_path(const std::string& path);

}  // namespace errfield::cli
