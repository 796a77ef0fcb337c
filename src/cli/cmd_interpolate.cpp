// `errfield interpolate`: predicts a value at every row of a targets CSV from a samples CSV, with
// one of the registered methods (interpolation_methods.hpp), and writes the targets' columns plus
// the predictions. With --grid the targets are the nodes of a regular 2-D grid, and the results
// may be written as a raster (GeoTIFF, ESRI ASCII grid; raster_file.hpp) instead of a CSV, and
// restricted to the nodes where a --mask raster has data. Samples and targets may be point layers
// (GeoPackage, shapefile, GeoJSON; point_layer.hpp), predictions at points may be written as a
// GeoPackage, and the CRS of the inputs (or --crs) goes into every raster and vector output.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <iostream>
#include <memory>
#include <optional>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/coordinate_system.hpp"
#include "cli/grid_map_svg.hpp"
#include "cli/interpolation_methods.hpp"
#include "cli/point_layer.hpp"
#include "cli/raster_file.hpp"
#include "cli/value_cells.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield::cli {
namespace {

// 4 million nodes (2,000 x 2,000): the targets table and every output band stay within a few
// hundred MB; --max-grid-nodes lifts it.
constexpr std::size_t kDefaultMaxGridNodes = 4'000'000;

struct InterpolateArgs {
  std::string method;
  std::string samples;
  std::string targets;
  std::string coords;
  std::string value;
  std::string out;
  std::string grid;           // --grid XMIN:XMAX:DX,YMIN:YMAX:DY, instead of --targets
  std::size_t max_grid_nodes = kDefaultMaxGridNodes;
  std::string raster_format;  // "" = by --out's extension
  std::string crs;            // --crs: the coordinates' CRS, written into raster and vector outputs
  std::string mask;           // --mask FILE: with --grid, predict only where this raster has data
  std::string plot;           // --plot FILE.svg: with --grid, the prediction map with the samples
  double nodata = -9999.0;
  double power = 0.0;
  std::size_t neighbors = 0;
  double radius = 0.0;
  bool clamp = false;
};

struct SharedOptionHandles {
  CLI::Option* power = nullptr;
  CLI::Option* neighbors = nullptr;
  CLI::Option* radius = nullptr;
  CLI::Option* clamp = nullptr;
  std::vector<CLI::Option*> all() const { return {power, neighbors, radius, clamp}; }
};

SharedInterpolationOptions read_shared(const InterpolateArgs& a, const SharedOptionHandles& h) {
  SharedInterpolationOptions s;
  if (h.power->count()) {
    if (!(a.power >= 0.0) || !std::isfinite(a.power))
      throw ArgumentError("--power is " + format_number(a.power) + "; expected a finite value >= 0");
    s.power = a.power;
  }
  if (h.neighbors->count()) {
    if (a.neighbors < 1) throw ArgumentError("--neighbors is 0; expected at least 1");
    s.neighbors = a.neighbors;
  }
  if (h.radius->count()) {
    if (!(a.radius > 0.0) || !std::isfinite(a.radius))
      throw ArgumentError("--radius is " + format_number(a.radius) + "; expected a finite value > 0");
    s.radius = a.radius;
  }
  s.clamp = a.clamp;
  return s;
}

std::vector<std::string> prediction_columns(const std::vector<std::string>& values) {
  if (values.size() == 1) return {"pred"};
  std::vector<std::string> names;
  for (const auto& v : values) names.push_back("pred_" + v);
  return names;
}

// The nodes of --grid as a targets table with the --coords columns, in raster order (row 0 the
// largest y): every method reads it as it reads a targets file. `keep` (one flag per node, empty:
// all) leaves out the nodes outside --mask.
CsvTable grid_targets(const NodeGrid& grid, const std::vector<std::string>& coords, const std::vector<char>& keep = {}) {
  std::string text;
  text.reserve(grid.size() * 24 + 64);
  append_csv_line(text, coords);
  for (std::size_t r = 0; r < grid.ny; ++r) {
    const std::string y = format_number(grid.y(r));
    for (std::size_t c = 0; c < grid.nx; ++c) {
      if (!keep.empty() && !keep[r * grid.nx + c]) continue;
      text += format_number(grid.x(c));
      text += ',';
      text += y;
      text += '\n';
    }
  }
  return CsvTable::parse(text, "--grid");
}

// The grid nodes where the --mask raster has data (pixel-is-area: the pixel that contains the node).
std::vector<char> nodes_inside_mask(const NodeGrid& grid, const CovariateRaster& mask) {
  std::vector<char> keep(grid.size());
  for (std::size_t r = 0; r < grid.ny; ++r)
    for (std::size_t c = 0; c < grid.nx; ++c) keep[r * grid.nx + c] = mask.has_data_at(grid.x(c), grid.y(r)) ? 1 : 0;
  return keep;
}

// The results at the nodes inside --mask spread over the whole grid, NaN (no prediction) outside.
void spread_to_grid(InterpolationResult& result, const std::vector<char>& keep) {
  const auto n = static_cast<Eigen::Index>(keep.size());
  Eigen::MatrixXd pred = Eigen::MatrixXd::Constant(n, result.pred.cols(), std::numeric_limits<double>::quiet_NaN());
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) at.push_back(i);
  for (std::size_t k = 0; k < at.size(); ++k) pred.row(static_cast<Eigen::Index>(at[k])) = result.pred.row(static_cast<Eigen::Index>(k));
  result.pred = std::move(pred);
  for (auto& [name, values] : result.extra_columns) {
    std::vector<double> full(keep.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t k = 0; k < at.size(); ++k) full[at[k]] = values[k];
    values = std::move(full);
  }
}

// " in CRS EPSG:27700 (OSGB36 / British National Grid)", or nothing without a CRS.
std::string crs_note(const CoordinateSystem& cs) { return cs.crs() ? " in CRS " + cs.crs()->label : std::string(); }

// The .prj file beside an ESRI ASCII grid: out.asc -> out.prj.
std::string prj_path(const std::string& path) {
  const auto dot = path.rfind('.');
  const auto slash = path.rfind('/');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  return (has_ext ? path.substr(0, dot) : path) + ".prj";
}

bool is_geopackage_path(const std::string& path) {
  if (path.size() < 5) return false;
  std::string ext = path.substr(path.size() - 5);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".gpkg";
}

// Where the results go: a CSV (the default) or a raster, by --raster-format or --out's extension.
std::optional<RasterFormat> output_raster_format(const InterpolateArgs& a) {
  if (a.raster_format == "csv") return std::nullopt;
  if (!a.raster_format.empty()) return raster_format_from_name(a.raster_format);
  return raster_format_of_path(a.out);
}

// An ESRI ASCII grid holds one band: the first column goes to --out, each further one to a file
// beside it named after the column (out.asc, out_var.asc).
std::string sibling_path(const std::string& out, const std::string& column) {
  const auto dot = out.rfind('.');
  const auto slash = out.rfind('/');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  return has_ext ? out.substr(0, dot) + "_" + column + out.substr(dot) : out + "_" + column;
}

// The results as a raster: one band per output column (predictions, then var, ...), descriptions
// set to the column names, empty cells as --nodata. A GeoTIFF holds every band; an ESRI ASCII grid
// one, so each further column goes to a file beside --out. All files are replaced together.
void write_raster(RasterFormat format, const NodeGrid& grid, const InterpolateArgs& a,
                  const std::vector<std::string>& pred_names, const InterpolationResult& result, Eigen::Index m,
                  const std::string& counts, std::size_t sample_count, const std::string& method,
                  const CoordinateSystem& cs, const std::string& svg) {
  std::vector<std::string> names = pred_names;
  std::vector<std::vector<double>> bands;
  for (std::size_t c = 0; c < pred_names.size(); ++c) {
    const Eigen::VectorXd column = result.pred.col(static_cast<Eigen::Index>(c));
    bands.emplace_back(column.data(), column.data() + m);
  }
  for (const auto& [name, values] : result.extra_columns) {
    names.push_back(name);
    bands.push_back(values);
  }
  for (std::size_t b = 0; b < bands.size(); ++b)
    for (std::size_t i = 0; i < bands[b].size(); ++i) {
      const double v = bands[b][i];
      if (v == a.nodata)
        throw Error("interpolate: " + names[b] + " at grid node " + std::to_string(i) + " is " + format_number(v) +
                    ", the --nodata value, which would read as 'no prediction'; give another --nodata; " + a.out + " not written");
      if (!std::isnan(v) && !std::isfinite(v)) OutputTable::check_finite_cell(names[b], i, format_number(v));
    }
  AtomicFileSet files;
  std::vector<std::string> written;
  std::vector<std::string> prj_files;
  if (format == RasterFormat::GeoTiff) {
    files.add(a.out, encode_raster(format, grid, names, bands, a.nodata, cs.crs()).bytes);
    written.push_back(a.out);
  } else {
    for (std::size_t b = 0; b < bands.size(); ++b) {
      const std::string path = b == 0 ? a.out : sibling_path(a.out, names[b]);
      EncodedRaster encoded = encode_raster(format, grid, {names[b]}, {bands[b]}, a.nodata, cs.crs());
      files.add(path, std::move(encoded.bytes));
      if (!encoded.prj.empty()) {
        files.add(prj_path(path), std::move(encoded.prj));
        prj_files.push_back(prj_path(path));
      }
      written.push_back(path);
    }
  }
  std::string text = "interpolate: the " + std::to_string(grid.nx) + " x " + std::to_string(grid.ny) +
                     " nodes of --grid from " + std::to_string(sample_count) + " samples with --method " + method + "; " +
                     counts + (counts.find("without") != std::string::npos || counts.find("outside") != std::string::npos ? " (nodata " + format_number(a.nodata) + ")" : "");
  text += "; wrote " + std::string(format == RasterFormat::GeoTiff ? "GeoTIFF " : "ESRI ASCII grid ");
  for (std::size_t k = 0; k < written.size(); ++k)
    text += (k ? ", " : "") + written[k] + " (" + names[format == RasterFormat::GeoTiff ? 0 : k] +
            (format == RasterFormat::GeoTiff && names.size() > 1 ? " and " + std::to_string(names.size() - 1) + " more bands" : "") + ")";
  if (!prj_files.empty()) {
    text += " with its CRS in ";
    for (std::size_t k = 0; k < prj_files.size(); ++k) text += (k ? ", " : "") + prj_files[k];
  }
  if (!svg.empty()) {
    files.add(a.plot, svg);
    text += " and the map " + a.plot;
  }
  commit_after_standard_output(files, text + crs_note(cs) + "\n");
}

// Predictions at points as a GeoPackage point layer: the targets' columns except the coordinates
// (the geometry holds them), then the predictions and the method's further columns.
void write_geopackage(const InterpolateArgs& a, const InterpolationRequest& r, const CsvTable& targets,
                      const std::vector<std::string>& pred_names, InterpolationResult& result, const std::string& summary,
                      const CoordinateSystem& cs) {
  std::vector<PointField> fields;
  for (std::size_t c = 0; c < targets.header().size(); ++c) {
    const std::string& name = targets.header()[c];
    if (std::find(r.coord_columns.begin(), r.coord_columns.end(), name) != r.coord_columns.end()) continue;
    PointField f{name, {}, {}, true};
    f.text.reserve(targets.row_count());
    for (std::size_t i = 0; i < targets.row_count(); ++i) f.text.emplace_back(targets.cell(i, c));
    fields.push_back(std::move(f));
  }
  for (std::size_t c = 0; c < pred_names.size(); ++c) {
    const auto column = result.pred.col(static_cast<Eigen::Index>(c));
    fields.push_back({pred_names[c], std::vector<double>(column.data(), column.data() + column.size()), {}, false});
  }
  for (auto& [name, values] : result.extra_columns) fields.push_back({name, std::move(values), {}, false});
  for (const auto& f : fields)
    if (!f.is_text)
      for (std::size_t i = 0; i < f.numbers.size(); ++i)
        if (!std::isnan(f.numbers[i]) && !std::isfinite(f.numbers[i])) OutputTable::check_finite_cell(f.name, i, format_number(f.numbers[i]));
  if (r.target_coords.cols() != 2 && r.target_coords.cols() != 3)
    throw ArgumentError("--out " + a.out + ": a GeoPackage holds 2-D or 3-D points; --coords names " +
                        std::to_string(r.target_coords.cols()) + " columns");
  const std::string layer = layer_name_of_path(a.out);
  AtomicFileSet files;
  files.add(a.out, encode_point_geopackage(layer, r.target_coords, fields, cs.crs()));
  commit_after_standard_output(files, summary + "; wrote GeoPackage " + a.out + " (layer '" + layer + "', " +
                                          std::to_string(r.target_coords.rows()) + " points)" + crs_note(cs) + "\n");
}

// Where the predictions go: a raster, a GeoPackage or a CSV; targets from a file or a --grid.
struct OutputShape {
  std::optional<RasterFormat> raster;
  bool geopackage = false;
  std::optional<NodeGrid> grid;
};

OutputShape output_shape(const InterpolateArgs& a) {
  if (a.targets.empty() == a.grid.empty())
    throw ArgumentError(a.grid.empty() ? "interpolate needs --targets FILE or --grid XMIN:XMAX:DX,YMIN:YMAX:DY"
                                       : "--targets and --grid both give the targets; give one of them");
  if (!a.mask.empty() && a.grid.empty())
    throw ArgumentError("--mask " + a.mask + " restricts the nodes of --grid; give --grid (with --targets, leave out the "
                        "points you do not want)");
  OutputShape o;
  o.raster = output_raster_format(a);
  o.geopackage = !o.raster && a.raster_format != "csv" && is_geopackage_path(a.out);
  if (!a.grid.empty()) o.grid = parse_node_grid(a.grid, "--grid", a.max_grid_nodes, "--max-grid-nodes");
  const auto& raster = o.raster;
  const auto& grid = o.grid;
  if (raster && !grid)
    throw ArgumentError("--out " + a.out + " is a raster (" + (*raster == RasterFormat::GeoTiff ? "GeoTIFF" : "ESRI ASCII grid") +
                        "); a raster needs targets on a grid: give --grid instead of --targets, or a .csv --out");
  if (raster && !rasters_available()) (void)encode_raster(*raster, *grid, {}, {}, a.nodata);  // names the missing GDAL
  if (raster && *raster == RasterFormat::EsriAscii && grid->dx != grid->dy)
    throw ArgumentError("--out " + a.out + ": an ESRI ASCII grid has square cells (one cellsize); --grid has dx " +
                        format_number(grid->dx) + " and dy " + format_number(grid->dy) +
                        ": give equal steps or write a GeoTIFF (.tif)");
  if (!std::isfinite(a.nodata)) throw ArgumentError("--nodata is " + format_number(a.nodata) + "; expected a finite number");
  if (!a.plot.empty() && !grid)
    throw ArgumentError("--plot " + a.plot + " draws the map of a --grid; with --targets there is no map (give --grid)");
  if (!a.plot.empty() && o.geopackage)
    throw ArgumentError("--plot " + a.plot + " with a GeoPackage --out: give a raster (.tif, .asc) or CSV --out with the map");
  if (!a.plot.empty() && a.plot == a.out) throw ArgumentError("--plot and --out are the same file " + a.out);
  return o;
}

void check_grid_size(const InterpolateArgs& a, const NodeGrid& grid, std::size_t coords) {
  if (coords != 2)
    throw ArgumentError("--grid is a 2-D grid; --coords names " + std::to_string(coords) + " columns, expected 2 (x,y)");
  if (grid.size() > a.max_grid_nodes)
    throw ResourceError("--grid " + a.grid + " has " + std::to_string(grid.nx) + " x " + std::to_string(grid.ny) +
                        " = " + std::to_string(grid.size()) + " nodes, more than --max-grid-nodes " +
                        std::to_string(a.max_grid_nodes) + "; give a coarser step or a larger --max-grid-nodes");
}

// --mask: the nodes predicted (those on a pixel with data); empty without --mask.
std::vector<char> mask_nodes(const InterpolateArgs& a, const std::optional<NodeGrid>& grid, CoordinateSystem& cs) {
  std::vector<char> inside;
  if (a.mask.empty()) return inside;
  const CovariateRaster mask = read_covariate_raster(a.mask);
  cs.add(mask.crs, "--mask " + a.mask, a.mask);
  inside = nodes_inside_mask(*grid, mask);
  if (std::find(inside.begin(), inside.end(), 1) == inside.end())
    throw InputError("--mask " + a.mask + ": none of the " + std::to_string(grid->size()) + " nodes of --grid " + a.grid +
                         " falls on a pixel with data; expected the grid and the mask to overlap",
                     a.mask);
  return inside;
}

// The samples and targets into the request (which points at both tables: they must outlive it).
void attach_tables(const InterpolateArgs& a, const PointTable& sample_points, bool gaps, const CsvTable& targets,
                   const std::optional<PointTable>& target_points, const std::vector<char>& inside,
                   InterpolationRequest& r) {
  const bool grid = !target_points;
  const CsvTable& samples = sample_points.table;
  if (samples.row_count() == 0) throw InputError(a.samples + ": no data rows; expected samples", a.samples);
  if (targets.row_count() == 0) throw InputError(a.targets + ": no data rows; expected targets", a.targets);
  r.samples = &samples;
  r.targets = &targets;
  r.sample_coords = samples.numeric_columns(r.coord_columns);
  r.sample_values = gaps ? numeric_columns_with_gaps(samples, r.value_columns) : samples.numeric_columns(r.value_columns);
  r.target_coords = targets.numeric_columns(r.coord_columns);
  r.sample_labels = sample_points.labels("sample");
  r.target_labels = grid ? RowLabels{{}, {}, "grid node"} : target_points->labels("target");  // "grid node 12", in raster order
  if (grid && !inside.empty()) {  // the node's index in the whole grid, not among those inside --mask
    r.target_labels = RowLabels{"--grid node", {}, "grid node"};
    for (std::size_t i = 0; i < inside.size(); ++i)
      if (inside[i]) r.target_labels.lines.push_back(i);
  }
}

// The prediction columns' names: the method's own, else pred (pred_<col>); refused when the
// targets already have them, and the result's size checked.
std::vector<std::string> checked_prediction_names(const InterpolateArgs& a, const InterpolationMethod& method,
                                                  const CsvTable& targets, const std::vector<std::string>& default_names,
                                                  const InterpolationResult& result) {
  const auto m = static_cast<Eigen::Index>(targets.row_count());
  const std::vector<std::string> pred_names = result.prediction_names.empty() ? default_names : result.prediction_names;
  for (const auto& name : result.prediction_names)
    if (targets.has_column(name))
      throw InputError(a.targets + ": already has a column '" + name + "', which the output would repeat; rename it",
                       a.targets, 1, name);
  if (result.pred.rows() != m || result.pred.cols() != static_cast<Eigen::Index>(pred_names.size()))
    throw Error("interpolate: method " + method.name + " returned " + std::to_string(result.pred.rows()) + " x " +
                std::to_string(result.pred.cols()) + " predictions; expected " + std::to_string(m) + " x " +
                std::to_string(pred_names.size()));
  return pred_names;
}

// Targets without a prediction; none predicted is a failed job, as in predict, validate and cv (a
// file of empty cells exited 0).
std::size_t count_missing(const InterpolateArgs& a, const InterpolationMethod& method, const InterpolationRequest& r,
                          const InterpolationResult& result, const std::string& targets_name, bool masked) {
  const Eigen::Index m = result.pred.rows();
  std::size_t missing = 0;
  for (Eigen::Index i = 0; i < m; ++i) missing += std::isnan(result.pred(i, 0)) ? 1 : 0;
  if (m > 0 && missing == static_cast<std::size_t>(m)) {
    std::string why;
    for (const auto& note : result.notes) why += "; " + note;
    if (r.shared.radius)
      why += "; no target has a sample within --radius " + format_number(*r.shared.radius) +
             " (in the scaled coordinates, where an anisotropy applies): a larger --radius or fewer targets far "
             "from the samples";
    throw Error("interpolate: none of the " + std::to_string(m) + (masked ? " unmasked" : "") + " targets of " +
                targets_name + " got a prediction with --method " + method.name + why + "; " + a.out + " not written");
  }
  return missing;
}

// The targets' columns, then the predictions and the method's extra columns, as numbers.
void write_csv_output(const InterpolateArgs& a, const CsvTable& written_targets, const std::vector<std::string>& pred_names,
                      InterpolationResult& result, const std::string& line, const std::string& svg) {
  OutputTable out;
  out.add_all_columns(written_targets);
  // Numbers, not text: formatted straight into the file (a NaN, not predicted, is an empty cell).
  for (std::size_t c = 0; c < pred_names.size(); ++c) {
    const auto column = result.pred.col(static_cast<Eigen::Index>(c));
    out.add_numbers(pred_names[c], std::vector<double>(column.data(), column.data() + column.size()));
  }
  for (auto& [name, values] : result.extra_columns) out.add_numbers(name, std::move(values));
  std::cout << line << "; wrote " << a.out << (svg.empty() ? std::string() : " and the map " + a.plot) << "\n";
  require_standard_output();  // before the write: a run that fails leaves the previous file
  if (svg.empty()) {
    out.write(a.out);
    return;
  }
  AtomicFileSet files;  // the table and the map: both or neither
  files.add(a.out, out.to_csv());
  files.add(a.plot, svg);
  files.commit();
}

// --plot: the map of the first prediction column over the whole grid, the samples on it.
std::string prediction_map(const InterpolateArgs& a, const NodeGrid& grid, const InterpolationRequest& r,
                           const std::vector<std::string>& pred_names, const InterpolationResult& result,
                           const std::string& method) {
  GridMapPlot map;
  map.nx = grid.nx;
  map.ny = grid.ny;
  map.x_min = grid.x_min;
  map.dx = grid.dx;
  map.y_min = grid.y_min;
  map.dy = grid.dy;
  const Eigen::VectorXd column = result.pred.col(0);
  map.values.assign(column.data(), column.data() + column.size());
  for (Eigen::Index i = 0; i < r.sample_coords.rows(); ++i) map.points.push_back({r.sample_coords(i, 0), r.sample_coords(i, 1)});
  map.x_label = r.coord_columns[0];
  map.y_label = r.coord_columns[1];
  map.value_label = pred_names.front();
  map.title = "interpolate --method " + method + ": " + pred_names.front() + " of " + a.value + " from " +
              std::to_string(r.sample_coords.rows()) + " samples (points)";
  return grid_map_svg_text(map);
}

void run_interpolate(const InterpolateArgs& a, const SharedOptionHandles& h, const MethodOptionOwnership& owners) {
  const InterpolationMethod& method = find_method(a.method, false);
  owners.check(method.name, method.accepts, h.all());

  InterpolationRequest r;
  r.value_columns = split_column_list(a.value, "--value");
  r.shared = read_shared(a, h);
  with_value_type(r.value_columns.size(), []<class V>() {});  // reject unsupported counts early
  const OutputShape shape = output_shape(a);
  const std::optional<NodeGrid>& grid = shape.grid;
  CoordinateSystem cs;
  if (!a.crs.empty()) cs.add(parse_crs(a.crs, "--crs"), "--crs");

  const bool gaps = method.takes_missing_values && method.takes_missing_values();
  const PointTable sample_points = read_point_table(a.samples, "--samples", {r.value_columns, gaps});
  const CsvTable& samples = sample_points.table;
  cs.add(sample_points.crs, "--samples " + a.samples, a.samples);
  r.coord_columns = sample_points.coordinate_columns(a.coords, "--coords");
  if (grid) check_grid_size(a, *grid, r.coord_columns.size());
  const std::vector<char> inside = mask_nodes(a, grid, cs);
  std::optional<PointTable> target_points;
  if (!grid) {
    target_points = read_point_table(a.targets, "--targets");
    cs.add(target_points->crs, "--targets " + a.targets, a.targets);
  }
  const CsvTable targets = grid ? grid_targets(*grid, r.coord_columns, inside) : target_points->table;
  const std::string targets_name = grid ? "--grid " + a.grid : a.targets;
  attach_tables(a, sample_points, gaps, targets, target_points, inside, r);
  r.coordinate_system = &cs;
  if (const std::string w = cs.geographic_warning(); !w.empty()) std::cerr << "errfield interpolate: " << w << "\n";

  const auto default_pred_names = prediction_columns(r.value_columns);
  for (const auto& name : default_pred_names)
    if (targets.has_column(name))
      throw InputError(a.targets + ": already has a column '" + name +
                           "', which the output would repeat; rename it",
                       a.targets, 1, name);

  InterpolationResult result = method.interpolate(r);
  const auto m = static_cast<Eigen::Index>(targets.row_count());
  const std::vector<std::string> pred_names = checked_prediction_names(a, method, targets, default_pred_names, result);
  const std::size_t missing = count_missing(a, method, r, result, targets_name, !inside.empty());
  std::string counts = std::to_string(static_cast<std::size_t>(m) - missing) + " predicted";
  if (!inside.empty()) counts += ", " + std::to_string(grid->size() - static_cast<std::size_t>(m)) + " outside --mask";
  if (missing) counts += ", " + std::to_string(missing) + " without prediction";
  for (const auto& note : result.notes) std::cerr << "errfield interpolate: " << note << "\n";
  // The whole grid from here on: the nodes outside --mask have no prediction.
  const CsvTable all_nodes = inside.empty() ? CsvTable() : grid_targets(*grid, r.coord_columns);
  if (!inside.empty()) spread_to_grid(result, inside);
  const CsvTable& written_targets = inside.empty() ? targets : all_nodes;
  const auto rows = static_cast<Eigen::Index>(written_targets.row_count());
  const std::string svg = a.plot.empty() ? std::string() : prediction_map(a, *grid, r, pred_names, result, method.name);
  if (shape.raster) {  // the bands straight from the numbers: no text cells for millions of nodes
    write_raster(*shape.raster, *grid, a, pred_names, result, rows, counts, samples.row_count(), method.name, cs, svg);
    return;
  }
  const std::string where = grid ? "the " + std::to_string(grid->nx) + " x " + std::to_string(grid->ny) + " nodes of --grid"
                                 : std::to_string(m) + " targets";
  const std::string summary = "interpolate: " + where + " from " + std::to_string(samples.row_count()) +
                              " samples with --method " + method.name + "; " + counts;
  if (shape.geopackage) {
    InterpolationRequest points = r;
    if (!inside.empty()) points.target_coords = all_nodes.numeric_columns(r.coord_columns);
    write_geopackage(a, points, written_targets, pred_names, result, summary, cs);
    return;
  }
  write_csv_output(a, written_targets, pred_names, result,
                   summary + (missing || !inside.empty() ? " (empty cells)" : ""), svg);
}

void add_interpolate_command(CLI::App& app) {
  auto args = std::make_shared<InterpolateArgs>();
  auto handles = std::make_shared<SharedOptionHandles>();
  CLI::App* cmd = app.add_subcommand("interpolate", "Predict values at target points from samples (IDW on a regular grid, scattered IDW, ...)");
  cmd->footer(
      "Methods:\n" +
      [] {
        std::string s;
        for (const auto& m : interpolation_methods())
          if (m.interpolate) s += "  " + m.name + ": " + m.summary + "\n";
        return s;
      }() +
      "\nThe output has every column of the targets file plus 'pred' (for --value dx,dy,dz: pred_dx,pred_dy,pred_dz);\n"
      "a target without a prediction gets empty cells; if no target gets one, nothing is written and the exit\n"
      "status is 1, with the reason. The output is written atomically.\n"
      "With --grid the targets are grid nodes (row by row from the largest y, x increasing); with --out F.tif or\n"
      "F.asc the columns pred, var, ... become raster bands (pixel centres at the nodes; docs/data-formats.md);\n"
      "--mask M.tif predicts only where M has data. Samples and targets may be point layers (GeoPackage,\n"
      "shapefile, GeoJSON); --out F.gpkg writes the predictions as a GeoPackage point layer. The CRS of the inputs\n"
      "(or --crs EPSG:NNNN) is written into every raster and GeoPackage; inputs in different CRSs are refused.\n\n"
      "Example (errors.csv, scattered.csv, targets.csv: SIMULATED, from scripts/make_example_error_field.py):\n"
      "  # the paper's method: distance errors measured on a 125 mm grid, interpolated to targets\n"
      "  errfield interpolate --method idw-grid --samples errors.csv --targets targets.csv \\\n"
      "      --coords x,y,z --value dL --out predicted.csv\n"
      "  errfield interpolate --method idw --samples scattered.csv --targets targets.csv \\\n"
      "      --coords x,y,z --value dx,dy,dz --neighbors 8 --power 2 --out predicted.csv\n");
  cmd->add_option("--method", args->method, "Interpolation method: " + method_names(false))->required();
  cmd->add_option("--samples", args->samples,
                  "Samples: a CSV (coordinates and values), or a point layer (.gpkg, .shp, .geojson: the coordinates are "
                  "the points', the values attributes)")->required();
  cmd->add_option("--targets", args->targets, "Points to predict at: a CSV (the coordinate columns) or a point layer; or --grid");
  cmd->add_option("--grid", args->grid,
                  "Targets on a regular 2-D grid instead of --targets: XMIN:XMAX:DX,YMIN:YMAX:DY, the nodes x = XMIN + "
                  "i*DX while x <= XMAX (XMAX is a node when it is a whole number of steps from XMIN), the same in y; "
                  "--coords names the two columns. A raster --out puts a pixel centred on each node");
  cmd->add_option("--mask", args->mask,
                  "--grid: predict only at the nodes that fall on a pixel with data of this raster (.tif, any raster GDAL "
                  "reads: outside it, nodata or NaN is masked out); the others are written as --nodata (empty cells in "
                  "a CSV). Its CRS must be that of the other inputs");
  cmd->add_option("--plot", args->plot,
                  "--grid: also write FILE.svg, the map of the first prediction column (pred, pred_<col> or p_lt_<T>) with "
                  "the samples as points, cells to scale, a colour bar (viridis); written together with --out (both or "
                  "neither)");
  cmd->add_option("--max-grid-nodes", args->max_grid_nodes, "--grid: refuse more nodes than this (exit 3; default 4000000)")
      ->check(kUnsignedInteger);
  cmd->add_option("--raster-format", args->raster_format,
                  "How --out is written: gtiff (GeoTIFF, every column a band) | aaigrid (ESRI ASCII grid, one file per "
                  "column: --out, then OUT_<column>.asc) | csv; default by --out's extension (.tif/.tiff, .asc, .gpkg, else CSV)")
      ->check(CLI::IsMember({"gtiff", "aaigrid", "csv"}));
  cmd->add_option("--nodata", args->nodata, "Raster --out: the value of a node without prediction (default -9999)");
  cmd->add_option("--crs", args->crs,
                  "The CRS of the coordinates (EPSG:NNNN, WKT or a PROJ string), written into raster and GeoPackage "
                  "outputs; default: the CRS of the inputs that have one (a point layer, a covariate or --mask raster), "
                  "which must all agree (errfield does not reproject)");
  cmd->add_option("--coords", args->coords,
                  "Coordinate columns, comma-separated (x,y,z; any number for scattered methods); default for a point "
                  "layer: its points' x,y (and z)");
  cmd->add_option("--value", args->value, "Value column (attribute of a point layer), or 2-3 comma-separated columns of a vector value")->required();
  cmd->add_option("--out", args->out,
                  "Output CSV; FILE.gpkg: a GeoPackage point layer of the targets with the predictions as attributes; "
                  "with --grid a raster: FILE.tif (GeoTIFF) or FILE.asc (ESRI ASCII grid)")->required();
  handles->power = cmd->add_option("--power", args->power, "Power p of the inverse-distance weights 1/d^p (default: 1 for idw-grid as in the paper, 2 for idw as in gstat)");
  handles->neighbors = cmd->add_option("--neighbors", args->neighbors, "Use the K nearest samples (scattered methods; default: all)")
                          ->check(kUnsignedInteger);
  handles->radius = cmd->add_option("--radius", args->radius, "Use only samples within this distance, in the coordinates' unit (scattered methods)");
  handles->clamp = cmd->add_flag("--clamp", args->clamp, "idw-grid: interpolate targets outside the grid from the nearest cell instead of failing");
  auto owners = std::make_shared<MethodOptionOwnership>(add_method_options(*cmd, false));
  cmd->callback([args, handles, owners] { run_interpolate(*args, *handles, *owners); });
}

Registration register_interpolate{"interpolate", 30, &add_interpolate_command};

}  // namespace
}  // namespace errfield::cli
