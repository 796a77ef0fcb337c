#pragma once
// The coordinate reference system (CRS) of a command's coordinates, for GIS users: declared with
// --crs (EPSG:NNNN, WKT or a PROJ string), carried by the inputs that have one (GeoTIFF
// covariates and masks, GeoPackage / shapefile / GeoJSON points), and written into every raster
// and vector output. errfield does not reproject: inputs in different CRSs are refused, naming
// both. Parsed and compared by GDAL's OSR (gdal_library.hpp), not by hand.

#include <optional>
#include <string>

namespace errfield::cli {

/// A CRS as GDAL describes it.
struct Crs {
  std::string wkt;          ///< WKT2 (2019), as written into output files
  std::string label;        ///< "EPSG:27700 (OSGB36 / British National Grid)", for messages
  bool geographic = false;  ///< latitude/longitude in degrees: distances are not in a length unit
};

/// The CRS of `text` (anything GDAL's OSRSetFromUserInput takes: EPSG:27700, WKT, a PROJ string).
/// Throws ArgumentError naming `option` when GDAL cannot read it or this build has no GDAL.
Crs parse_crs(const std::string& text, const std::string& option);

/// True when GDAL considers a and b the same CRS (OSRIsSame; the same EPSG code written as WKT1,
/// WKT2 or by its code is the same).
bool same_crs(const Crs& a, const Crs& b);

/// The one CRS the inputs of a command agree on. add() each source in turn; the first CRS given is
/// kept, and one that differs is refused naming both sources and both CRSs.
class CoordinateSystem {
 public:
  /// `source` says where `crs` came from: "--crs", "--samples pts.gpkg", "covariate raster c.tif".
  /// No CRS (an input without one, such as a CSV) agrees with everything. Throws InputError (naming
  /// `file` when not empty) on a mismatch.
  void add(const std::optional<Crs>& crs, const std::string& source, const std::string& file = "");
  const std::optional<Crs>& crs() const { return crs_; }
  /// The WKT written into outputs, empty when no input has a CRS.
  std::string wkt() const { return crs_ ? crs_->wkt : std::string(); }
  /// Where the CRS came from (the first source that had it).
  const std::string& source() const { return source_; }
  /// For a geographic CRS (degrees of latitude and longitude), a warning that distances, radii and
  /// variogram ranges are then in degrees; empty otherwise. Printed, not refused: a small area near
  /// the equator is a fair approximation, and the user may know it.
  std::string geographic_warning() const;

 private:
  std::optional<Crs> crs_;
  std::string source_;
};

}  // namespace errfield::cli
