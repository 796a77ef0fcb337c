// Node grids and raster files (raster_file.hpp). Compiled on its own (not in a unity batch) with
// GDAL's headers, loaded at run time (gdal_library.hpp); it compiles without them, refusing rasters
// by name.

#include "cli/raster_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <utility>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

#ifdef ERRFIELD_HAVE_GDAL
#include "cli/gdal_library.hpp"
#endif

namespace errfield::cli {
namespace {

double grid_number(std::string_view part, std::string_view option, std::string_view what) {
  const std::string text(part);
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && std::isfinite(v)) return v;
  } catch (const std::exception&) {
  }
  throw ArgumentError(std::string(option) + ": " + std::string(what) + " is '" + text + "'; expected a finite number");
}

// One axis "MIN:MAX:STEP": the node count n with MIN + (n-1)*STEP <= MAX (+ 1e-9 STEP), as a
// double: it may be beyond any integer type (1e300 nodes, or inf when MAX - MIN overflows), which
// the caller's node budget refuses.
double parse_axis(std::string_view text, std::string_view option, char axis, double& min, double& step) {
  const std::string name(1, axis);
  std::vector<std::string_view> parts;
  for (std::size_t start = 0;;) {
    const auto colon = text.find(':', start);
    parts.push_back(text.substr(start, colon == std::string_view::npos ? std::string_view::npos : colon - start));
    if (colon == std::string_view::npos) break;
    start = colon + 1;
  }
  if (parts.size() != 3)
    throw ArgumentError(std::string(option) + ": the " + name + " axis is '" + std::string(text) + "'; expected " +
                        static_cast<char>(std::toupper(axis)) + "MIN:" + static_cast<char>(std::toupper(axis)) +
                        "MAX:D" + static_cast<char>(std::toupper(axis)));
  auto trim = [](std::string_view s) {
    while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
    while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
    return s;
  };
  min = grid_number(trim(parts[0]), option, name + "min");
  const double max = grid_number(trim(parts[1]), option, name + "max");
  step = grid_number(trim(parts[2]), option, "d" + name);
  if (!(step > 0.0)) throw ArgumentError(std::string(option) + ": d" + name + " is " + format_number(step) + "; expected > 0");
  if (max < min)
    throw ArgumentError(std::string(option) + ": " + name + "max " + format_number(max) + " is below " + name + "min " +
                        format_number(min));
  const double spans = (max - min) / step;
  return std::floor(spans + 1e-9) + 1.0;
}

}  // namespace

NodeGrid parse_node_grid(std::string_view text, std::string_view option, std::size_t max_nodes,
                         std::string_view max_option) {
  const auto comma = text.find(',');
  if (comma == std::string_view::npos || text.find(',', comma + 1) != std::string_view::npos)
    throw ArgumentError(std::string(option) + " is '" + std::string(text) +
                        "'; expected XMIN:XMAX:DX,YMIN:YMAX:DY (a 2-D grid)");
  NodeGrid g;
  const double nx = parse_axis(text.substr(0, comma), option, 'x', g.x_min, g.dx);
  const double ny = parse_axis(text.substr(comma + 1), option, 'y', g.y_min, g.dy);
  // Counted in double: a size_t product of two huge axes wraps round (2^40 x 2^40 is 0) and
  // would pass the budget. Every grid over it is one error, however large (1e18, 1e300, inf).
  const double nodes = nx * ny;
  constexpr double kExact = 9007199254740992.0;  // 2^53: the count and its size_t product stay exact
  if (!(nodes <= static_cast<double>(max_nodes) && nodes <= kExact))
    throw ResourceError(std::string(option) + " " + std::string(text) + " has " + format_number(nx) + " x " +
                        format_number(ny) + " = " + format_number(nodes) + " nodes, more than " +
                        std::string(max_option) + " " + std::to_string(max_nodes) + "; give a coarser step or a larger " +
                        std::string(max_option));
  g.nx = static_cast<std::size_t>(nx);
  g.ny = static_cast<std::size_t>(ny);
  return g;
}

std::optional<RasterFormat> raster_format_of_path(const std::string& path) {
  const auto dot = path.rfind('.');
  const auto slash = path.rfind('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return std::nullopt;
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == "tif" || ext == "tiff") return RasterFormat::GeoTiff;
  if (ext == "asc") return RasterFormat::EsriAscii;
  return std::nullopt;
}

RasterFormat raster_format_from_name(const std::string& name) {
  if (name == "gtiff") return RasterFormat::GeoTiff;
  if (name == "aaigrid") return RasterFormat::EsriAscii;
  throw ArgumentError("--raster-format is '" + name + "'; expected gtiff (GeoTIFF) or aaigrid (ESRI ASCII grid)");
}

namespace {

// The pixel (column, row) of a raster that contains (x, y), or none outside it.
std::optional<std::pair<std::size_t, std::size_t>> pixel_of(const CovariateRaster& r, double x, double y) {
  const double fx = (x - r.geo[0]) / r.geo[1];
  const double fy = (y - r.geo[3]) / r.geo[5];
  constexpr double kEdge = 1e-9;  // of a pixel: a point on the outer edge is still inside
  const double nx = static_cast<double>(r.cols), ny = static_cast<double>(r.rows);
  if (!(fx >= -kEdge && fx <= nx + kEdge && fy >= -kEdge && fy <= ny + kEdge)) return std::nullopt;
  return std::pair{static_cast<std::size_t>(std::clamp(std::floor(fx), 0.0, nx - 1.0)),
                   static_cast<std::size_t>(std::clamp(std::floor(fy), 0.0, ny - 1.0))};
}

}  // namespace

double CovariateRaster::at(double x, double y, const std::string& label) const {
  const auto pixel = pixel_of(*this, x, y);
  if (!pixel) {
    const double x1 = geo[0] + static_cast<double>(cols) * geo[1], y1 = geo[3] + static_cast<double>(rows) * geo[5];
    throw InputError(label + ": the point (" + format_number(x) + ", " + format_number(y) + ") is outside the raster " +
                         path + " (x " + format_number(std::min(geo[0], x1)) + " to " + format_number(std::max(geo[0], x1)) +
                         ", y " + format_number(std::min(geo[3], y1)) + " to " + format_number(std::max(geo[3], y1)) +
                         "); errfield does not extrapolate a covariate",
                     path);
  }
  const auto [col, row] = *pixel;
  const double v = values[row * cols + col];
  if (std::isnan(v) || (nodata && v == *nodata))
    throw InputError(label + ": the point (" + format_number(x) + ", " + format_number(y) + ") falls on a nodata pixel (column " +
                         std::to_string(col) + ", row " + std::to_string(row) + ", 0-based) of the raster " + path,
                     path);
  return v;
}

bool CovariateRaster::has_data_at(double x, double y) const {
  const auto pixel = pixel_of(*this, x, y);
  if (!pixel) return false;
  const double v = values[pixel->second * cols + pixel->first];
  return !std::isnan(v) && !(nodata && v == *nodata);
}

#ifdef ERRFIELD_HAVE_GDAL

namespace {

using namespace gdal_detail;

// Opens a raster for reading: GeoTIFF and ESRI ASCII grids with the drivers registered, any other
// format after registering all of GDAL's drivers.
GDALDatasetH open_raster(const std::string& path) {
  const GdalApi& g = start_gdal();
  if (GDALDatasetH h = g.GDALOpen(path.c_str(), GA_ReadOnly)) return h;
  register_all_drivers();
  return g.GDALOpen(path.c_str(), GA_ReadOnly);
}

}  // namespace

bool rasters_available() { return true; }

EncodedRaster encode_raster(RasterFormat format, const NodeGrid& grid, const std::vector<std::string>& names,
                            const std::vector<std::vector<double>>& bands, double nodata, const std::optional<Crs>& crs) {
  if (bands.empty() || bands.size() != names.size()) throw Error("encode_raster: band names and bands differ in number");
  for (const auto& b : bands)
    if (b.size() != grid.size()) throw Error("encode_raster: a band has " + std::to_string(b.size()) + " values for " +
                                             std::to_string(grid.size()) + " nodes");
  if (format == RasterFormat::EsriAscii) {
    if (bands.size() != 1) throw Error("encode_raster: an ESRI ASCII grid holds one band");
    if (grid.dx != grid.dy)
      throw ArgumentError("an ESRI ASCII grid has square cells (one cellsize); --grid has dx " + format_number(grid.dx) +
                          " and dy " + format_number(grid.dy) + ": give equal steps or write a GeoTIFF (.tif)");
  }
  (void)start_gdal();
  const int nx = static_cast<int>(grid.nx), ny = static_cast<int>(grid.ny);
  // Pixel-is-area: each node is the centre of its cell.
  double geo[6] = {grid.x_min - grid.dx / 2.0, grid.dx, 0.0, grid.y(0) + grid.dy / 2.0, 0.0, -grid.dy};
  const bool tiff = format == RasterFormat::GeoTiff;
  const std::string name = vsimem_name(tiff ? ".tif" : ".asc");
  GDALDriverH mem = gdal().GDALGetDriverByName("MEM");
  GDALDriverH out = gdal().GDALGetDriverByName(tiff ? "GTiff" : "AAIGrid");
  if (!mem || !out) throw Error(std::string("raster: GDAL has no ") + (tiff ? "GTiff" : "AAIGrid") + " driver" + gdal_message());
  Dataset src(gdal().GDALCreate(mem, "", nx, ny, static_cast<int>(bands.size()), GDT_Float64, nullptr));
  if (!src.h) throw ResourceError("raster: cannot hold " + std::to_string(grid.size()) + " nodes in memory" + gdal_message());
  gdal().GDALSetGeoTransform(src.h, geo);
  if (crs) {
    OGRSpatialReferenceH srs = new_spatial_reference(*crs);
    const CPLErr set = gdal().GDALSetSpatialRef(src.h, srs);
    gdal().OSRDestroySpatialReference(srs);
    if (set != CE_None) throw Error("raster: GDAL could not set the CRS " + crs->label + gdal_message());
  }
  std::vector<double> row_values(grid.nx);
  for (std::size_t b = 0; b < bands.size(); ++b) {
    GDALRasterBandH band = gdal().GDALGetRasterBand(src.h, static_cast<int>(b) + 1);
    gdal().GDALSetDescription(band, names[b].c_str());
    gdal().GDALSetRasterNoDataValue(band, nodata);
    for (std::size_t r = 0; r < grid.ny; ++r) {
      for (std::size_t c = 0; c < grid.nx; ++c) {
        const double v = bands[b][r * grid.nx + c];
        row_values[c] = std::isnan(v) ? nodata : v;
      }
      if (gdal().GDALRasterIO(band, GF_Write, 0, static_cast<int>(r), nx, 1, row_values.data(), nx, 1, GDT_Float64, 0, 0) != CE_None)
        throw Error("raster: writing row " + std::to_string(r) + " failed" + gdal_message());
    }
  }
  // 17 significant digits: every double reads back exactly, as the CSV's shortest round-trip text.
  const char* tiff_options[] = {"COMPRESS=DEFLATE", "PREDICTOR=3", "INTERLEAVE=BAND", nullptr};
  const char* ascii_options[] = {"SIGNIFICANT_DIGITS=17", nullptr};
  Dataset copy(gdal().GDALCreateCopy(out, name.c_str(), src.h, FALSE, const_cast<char**>(tiff ? tiff_options : ascii_options),
                              nullptr, nullptr));
  if (!copy.h) throw Error("raster: GDAL could not write the " + std::string(tiff ? "GeoTIFF" : "ESRI ASCII grid") + gdal_message());
  copy.close();  // flushes into the memory file
  EncodedRaster encoded;
  encoded.bytes = take_memory_file(name);
  // An ESRI ASCII grid keeps its CRS in a .prj file beside it, which GDAL wrote with the grid.
  const std::string prj = name.substr(0, name.size() - 4) + ".prj";
  vsi_l_offset length = 0;
  if (gdal().VSIGetMemFileBuffer(prj.c_str(), &length, FALSE)) encoded.prj = take_memory_file(prj);
  if (crs && !tiff && encoded.prj.empty()) throw Error("raster: GDAL wrote no .prj file for the CRS " + crs->label + gdal_message());
  return encoded;
}

CovariateRaster read_covariate_raster(const std::string& path) {
  Dataset ds(open_raster(path));
  if (!ds.h) throw InputError(path + ": cannot be read as a raster" + gdal_message(), path);
  CovariateRaster r;
  r.path = path;
  r.cols = static_cast<std::size_t>(gdal().GDALGetRasterXSize(ds.h));
  r.rows = static_cast<std::size_t>(gdal().GDALGetRasterYSize(ds.h));
  if (gdal().GDALGetRasterCount(ds.h) < 1 || r.cols == 0 || r.rows == 0) throw InputError(path + ": the raster has no band", path);
  if (r.cols * r.rows > 100'000'000)
    throw ResourceError(path + ": " + std::to_string(r.cols) + " x " + std::to_string(r.rows) +
                        " pixels; errfield reads covariate rasters of up to 100 million pixels: crop or resample it "
                        "(gdal_translate -projwin / -tr)");
  if (gdal().GDALGetGeoTransform(ds.h, r.geo) != CE_None)
    throw InputError(path + ": the raster has no georeferencing (geotransform); errfield cannot place the points on it", path);
  if (r.geo[2] != 0.0 || r.geo[4] != 0.0 || r.geo[1] == 0.0 || r.geo[5] == 0.0)
    throw InputError(path + ": the raster's geotransform is rotated or degenerate; warp it to north-up first (gdalwarp)", path);
  GDALRasterBandH band = gdal().GDALGetRasterBand(ds.h, 1);
  int has_nodata = 0;
  const double nodata = gdal().GDALGetRasterNoDataValue(band, &has_nodata);
  if (has_nodata) r.nodata = nodata;
  r.crs = optional_crs_of(gdal().GDALGetSpatialRef(ds.h));
  r.values.resize(r.cols * r.rows);
  if (gdal().GDALRasterIO(band, GF_Read, 0, 0, static_cast<int>(r.cols), static_cast<int>(r.rows), r.values.data(),
                   static_cast<int>(r.cols), static_cast<int>(r.rows), GDT_Float64, 0, 0) != CE_None)
    throw InputError(path + ": reading the raster's first band failed" + gdal_message(), path);
  return r;
}

#else  // built without GDAL

namespace {
[[noreturn]] void no_gdal(const std::string& what) {
  throw ArgumentError(what + ": this errfield was built without GDAL (Debian's libgdal-dev), which reads and writes "
                      "GeoTIFF and ESRI ASCII grids; install it and build again (scripts/setup.sh), or use CSV");
}
}  // namespace

bool rasters_available() { return false; }

EncodedRaster encode_raster(RasterFormat, const NodeGrid&, const std::vector<std::string>&,
                            const std::vector<std::vector<double>>&, double, const std::optional<Crs>&) {
  no_gdal("writing a raster");
}

CovariateRaster read_covariate_raster(const std::string& path) { no_gdal(path); }

#endif

}  // namespace errfield::cli
