#pragma once
// Grids of target nodes (`interpolate --grid`) and the rasters a GIS opens: results written as a
// GeoTIFF or an ESRI ASCII grid, and covariates for external drift read from one. The raster
// formats go through GDAL (Debian's libgdal-dev); a build without it refuses them by name.
//
// Convention (docs/data-formats.md, "Grids and rasters"): a grid is a set of nodes
// x = XMIN + i*DX (i = 0, 1, ... while x <= XMAX, with a tolerance of 1e-9 DX), the same in y.
// A raster written from it has pixel-is-area cells of DX x DY centred on the nodes (GDAL's
// convention): the geotransform's origin is (XMIN - DX/2, y_top + DY/2), y_top the largest node y,
// and row 0 is the northern row.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli/coordinate_system.hpp"
#include "errfield/row_labels.hpp"

namespace errfield::cli {

/// A regular 2-D grid of nodes in raster order: row 0 is the largest y, columns go east.
struct NodeGrid {
  double x_min = 0.0, dx = 1.0;
  double y_min = 0.0, dy = 1.0;
  std::size_t nx = 0, ny = 0;

  std::size_t size() const { return nx * ny; }
  /// x of column `col` (0-based): x_min + col*dx, computed per node (no summed rounding).
  double x(std::size_t col) const { return x_min + static_cast<double>(col) * dx; }
  /// y of row `row`; row 0 is the top (northern) row of the raster.
  double y(std::size_t row) const { return y_min + static_cast<double>(ny - 1 - row) * dy; }
};

/// Parses "XMIN:XMAX:DX,YMIN:YMAX:DY" (the text of `option`). Throws ArgumentError naming the
/// option and the bad part (not a number, DX <= 0, XMAX < XMIN); ResourceError (exit 3) naming
/// `max_option` when the grid has more than `max_nodes` nodes, however many (1e300, or an
/// overflowing XMAX - XMIN).
NodeGrid parse_node_grid(std::string_view text, std::string_view option, std::size_t max_nodes,
                         std::string_view max_option);

enum class RasterFormat { GeoTiff, EsriAscii };

/// The raster format an output path asks for by its extension (.tif, .tiff: GeoTIFF; .asc: ESRI
/// ASCII grid; case-insensitive), or none (a CSV or any other name).
std::optional<RasterFormat> raster_format_of_path(const std::string& path);
/// "gtiff" / "aaigrid" as --raster-format takes them; throws ArgumentError for another word.
RasterFormat raster_format_from_name(const std::string& name);

/// True when this build can read and write rasters (it was built with GDAL).
bool rasters_available();

/// A raster file's bytes, and those of the .prj file beside it (an ESRI ASCII grid with a CRS).
struct EncodedRaster {
  std::string bytes;
  std::string prj;  ///< empty: no side file
};

/// The bytes of a raster file of `grid` in `format`, one band per entry of `bands` (each
/// grid.size() values in raster order; NaN is written as `nodata`), band descriptions `names`,
/// in `crs` when given (a GeoTIFF holds it; an ESRI ASCII grid has it in the .prj beside it).
/// GeoTIFF: Float64, all bands in one file. ESRI ASCII grid holds one band: `bands` must have one
/// entry, and the cells must be square (dx == dy), else ArgumentError. Written in memory (GDAL's
/// /vsimem), so that the caller commits it atomically with AtomicFileSet.
EncodedRaster encode_raster(RasterFormat format, const NodeGrid& grid, const std::vector<std::string>& names,
                            const std::vector<std::vector<double>>& bands, double nodata,
                            const std::optional<Crs>& crs = std::nullopt);

/// The first band of a georeferenced raster file, for looking values up at points.
struct CovariateRaster {
  std::string path;
  std::size_t cols = 0, rows = 0;
  double geo[6] = {0, 1, 0, 0, 0, 1};  ///< GDAL geotransform (no rotation)
  std::vector<double> values;           ///< rows x cols, row-major
  std::optional<double> nodata;
  std::optional<Crs> crs;               ///< none when the file has no CRS

  /// True when (x, y) falls on a pixel with data: inside the raster, not nodata, not NaN (a mask).
  bool has_data_at(double x, double y) const;

  /// The value of the pixel that contains (x, y) (pixel-is-area; a point on the raster's outer
  /// edge belongs to the edge pixel, one on an inner edge to the pixel east / south of it, as
  /// gdallocationinfo). Throws InputError naming `label` (the sample or target), the point and the
  /// raster's extent when the point is outside, or the pixel when it is nodata.
  double at(double x, double y, const std::string& label) const;
};

/// Reads `path` with GDAL. Throws InputError when it is not a raster GDAL reads, has no
/// georeferencing or a rotated one; ResourceError past 100 million pixels.
CovariateRaster read_covariate_raster(const std::string& path);

}  // namespace errfield::cli
