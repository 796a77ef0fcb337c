// Point layers through GDAL's OGR (point_layer.hpp). Compiled on its own with GDAL's headers
// (gdal_library.hpp); without GDAL a vector file is refused by name.

#include "cli/point_layer.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>

#include "errfield/csv_writing.hpp"
#include "errfield/error.hpp"

#ifdef ERRFIELD_HAVE_GDAL
#include "cli/gdal_library.hpp"
#endif

namespace errfield::cli {

bool is_vector_path(const std::string& path) {
  const auto dot = path.rfind('.');
  const auto slash = path.rfind('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return false;
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {"gpkg", "shp", "geojson", "json", "fgb", "gml", "kml", "sqlite"})
    if (ext == e) return true;
  return false;
}

std::string layer_name_of_path(const std::string& path) {
  const auto slash = path.rfind('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const auto dot = name.rfind('.');
  if (dot != std::string::npos && dot > 0) name = name.substr(0, dot);
  return name.empty() ? "points" : name;
}

std::vector<std::string> PointTable::coordinate_columns(const std::string& coords_option, const std::string& option) const {
  if (!coords_option.empty()) return split_column_list(coords_option, option);
  if (geometry_columns.empty())
    throw ArgumentError(table.source() + " is a CSV: give its coordinate columns with " + option +
                        " (a vector layer's points give them: x, y, z)");
  return geometry_columns;
}

RowLabels PointTable::labels(std::string noun) const {
  RowLabels l;
  l.noun = std::move(noun);
  if (layer.empty()) {
    l.source = table.source();
    l.lines.resize(table.row_count());
    for (std::size_t i = 0; i < table.row_count(); ++i) l.lines[i] = table.line_of_row(i);
  } else {
    l.source = table.source() + " layer '" + layer + "' FID";
    l.lines.assign(feature_ids.begin(), feature_ids.end());
  }
  return l;
}

#ifdef ERRFIELD_HAVE_GDAL

namespace {

using namespace gdal_detail;

// A feature that is destroyed however the scope is left.
struct Feature {
  OGRFeatureH h;
  explicit Feature(OGRFeatureH handle) : h(handle) {}
  ~Feature() {
    if (h) gdal().OGR_F_Destroy(h);
  }
  Feature(const Feature&) = delete;
  Feature& operator=(const Feature&) = delete;
};

bool is_geometry_name(const std::string& field, bool three_d) {
  const std::string key = column_key(field);
  std::string lower = key;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lower == "x" || lower == "y" || (three_d && lower == "z");
}

// errfield reads a file of one point layer; several are refused, naming them.
OGRLayerH single_layer(const GdalApi& g, GDALDatasetH ds, const std::string& path, const std::string& option) {
  const int layers = g.GDALDatasetGetLayerCount(ds);
  if (layers != 1) {
    std::string names;
    for (int i = 0; i < layers; ++i) names += (i ? ", " : "") + std::string(g.OGR_L_GetName(g.GDALDatasetGetLayer(ds, i)));
    throw InputError(option + " " + path + ": holds " + std::to_string(layers) + " layers" +
                         (names.empty() ? "" : " (" + names + ")") +
                         "; errfield reads a file of one point layer: extract it (ogr2ogr points.gpkg " + path + " LAYER)",
                     path);
  }
  return g.GDALDatasetGetLayer(ds, 0);
}

struct LayerFields {
  std::vector<std::string> names;
  std::vector<OGRFieldType> types;
};

LayerFields layer_fields(const GdalApi& g, OGRLayerH layer) {
  OGRFeatureDefnH defn = g.OGR_L_GetLayerDefn(layer);
  const int field_count = g.OGR_FD_GetFieldCount(defn);
  LayerFields fields;
  for (int f = 0; f < field_count; ++f) {
    OGRFieldDefnH fd = g.OGR_FD_GetFieldDefn(defn, f);
    fields.names.emplace_back(g.OGR_Fld_GetNameRef(fd));
    fields.types.push_back(g.OGR_Fld_GetType(fd));
  }
  return fields;
}

// The indices of the fields read as numbers (--value): each must exist and be numeric.
std::vector<int> required_field_indices(const LayerFields& fields, const RequiredFields& required,
                                        const std::string& where, const std::string& path) {
  const auto& field_names = fields.names;
  std::vector<int> required_index;
  for (const auto& name : required.numeric) {
    const auto it = std::find_if(field_names.begin(), field_names.end(),
                                 [&](const std::string& f) { return column_key(f) == column_key(name); });
    if (it == field_names.end()) {
      std::string list;
      for (const auto& f : field_names) list += (list.empty() ? "" : ", ") + f;
      throw InputError(where + ": has no field '" + name + "'; its fields: " + (list.empty() ? "none" : list), path, 0, name);
    }
    const auto t = fields.types[static_cast<std::size_t>(it - field_names.begin())];
    if (t != OFTReal && t != OFTInteger && t != OFTInteger64)
      throw InputError(where + ": field '" + *it + "' holds text, not numbers; expected a numeric field (Real or Integer)", path, 0,
                       name);
    required_index.push_back(static_cast<int>(it - field_names.begin()));
  }
  return required_index;
}

// A feature's geometry: a point, 2-D or 3-D like the features before it (`three_d`).
OGRGeometryH point_geometry(const GdalApi& g, OGRFeatureH feature, const std::string& at, const std::string& path,
                            long long fid, std::optional<bool>& three_d) {
  OGRGeometryH geometry = g.OGR_F_GetGeometryRef(feature);
  if (!geometry || g.OGR_G_IsEmpty(geometry))
    throw InputError(at + ": has no geometry; expected a point", path, static_cast<std::size_t>(fid));
  const OGRwkbGeometryType type = g.OGR_G_GetGeometryType(geometry);
  if (g.OGR_GT_Flatten(type) != wkbPoint)
    throw InputError(at + ": the geometry is a " + std::string(g.OGRGeometryTypeToName(type)) +
                         "; expected a Point (a multipoint: ogr2ogr -explodecollections; a polygon: its centroid, "
                         "ogr2ogr -dialect sqlite -sql 'SELECT ST_Centroid(geometry), * FROM layer')",
                     path, static_cast<std::size_t>(fid));
  const bool has_z = g.OGR_GT_HasZ(type) != 0;
  if (three_d && *three_d != has_z)
    throw InputError(at + ": is a " + std::string(has_z ? "3-D" : "2-D") + " point among " + (has_z ? "2-D" : "3-D") +
                         " ones; expected all points alike",
                     path, static_cast<std::size_t>(fid));
  three_d = has_z;
  return geometry;
}

// Each field's text after the point's coordinates (numbers in shortest round-trip form; null: empty).
void append_field_cells(const GdalApi& g, OGRFeatureH feature, const LayerFields& fields, bool has_z,
                        const std::string& at, const std::string& path, long long fid, std::vector<std::string>& cells) {
  const auto& field_names = fields.names;
  for (int f = 0; f < static_cast<int>(field_names.size()); ++f) {
    if (is_geometry_name(field_names[static_cast<std::size_t>(f)], has_z)) continue;
    if (!g.OGR_F_IsFieldSetAndNotNull(feature, f)) {
      cells.emplace_back();
      continue;
    }
    switch (fields.types[static_cast<std::size_t>(f)]) {
      case OFTReal: {
        const double v = g.OGR_F_GetFieldAsDouble(feature, f);
        if (!std::isfinite(v))
          throw InputError(at + ": field '" + field_names[static_cast<std::size_t>(f)] + "' is " + format_number(v) +
                               "; expected a finite number or null",
                           path, static_cast<std::size_t>(fid), field_names[static_cast<std::size_t>(f)]);
        cells.push_back(format_number(v));
        break;
      }
      case OFTInteger:
      case OFTInteger64: cells.push_back(std::to_string(g.OGR_F_GetFieldAsInteger64(feature, f))); break;
      default: cells.emplace_back(g.OGR_F_GetFieldAsString(feature, f)); break;
    }
  }
}

}  // namespace

PointTable read_point_table(const std::string& path, const std::string& option, const RequiredFields& required) {
  if (!is_vector_path(path)) {
    PointTable p;
    p.table = CsvTable::read(path);
    return p;
  }
  const GdalApi& g = start_gdal();
  register_all_drivers();
  Dataset ds(g.GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds.h) throw InputError(option + " " + path + ": cannot be read as a vector layer" + gdal_message(), path);
  OGRLayerH layer = single_layer(g, ds.h, path, option);
  PointTable p;
  p.layer = g.OGR_L_GetName(layer);
  p.crs = optional_crs_of(g.OGR_L_GetSpatialRef(layer));
  const std::string where = path + ", layer '" + p.layer + "'";
  const LayerFields fields = layer_fields(g, layer);
  const std::vector<int> required_index = required_field_indices(fields, required, where, path);

  // Every feature: its point, then each field's text (numbers in shortest round-trip form).
  std::vector<std::vector<std::string>> rows;
  std::optional<bool> three_d;
  g.OGR_L_ResetReading(layer);
  for (;;) {
    Feature feature(g.OGR_L_GetNextFeature(layer));
    if (!feature.h) break;
    const long long fid = static_cast<long long>(g.OGR_F_GetFID(feature.h));
    const std::string at = where + ", feature FID " + std::to_string(fid);
    OGRGeometryH geometry = point_geometry(g, feature.h, at, path, fid, three_d);
    const bool has_z = *three_d;
    for (const int f : required_index)
      if (!g.OGR_F_IsFieldSetAndNotNull(feature.h, f) && !required.allow_null)
        throw InputError(at + ": field '" + fields.names[static_cast<std::size_t>(f)] + "' is null; expected a number", path,
                         static_cast<std::size_t>(fid), fields.names[static_cast<std::size_t>(f)]);
    std::vector<std::string> cells{format_number(g.OGR_G_GetX(geometry, 0)), format_number(g.OGR_G_GetY(geometry, 0))};
    if (has_z) cells.push_back(format_number(g.OGR_G_GetZ(geometry, 0)));
    append_field_cells(g, feature.h, fields, has_z, at, path, fid, cells);
    p.feature_ids.push_back(fid);
    rows.push_back(std::move(cells));
  }
  p.geometry_columns = {"x", "y"};
  if (three_d.value_or(false)) p.geometry_columns.push_back("z");
  std::vector<std::string> header = p.geometry_columns;
  for (const auto& f : fields.names)
    if (!is_geometry_name(f, three_d.value_or(false))) header.push_back(f);
  std::string text;
  append_csv_line(text, header);
  for (const auto& row : rows) append_csv_line(text, row);
  p.table = CsvTable::parse(text, path);
  return p;
}

namespace {

// How a text column is stored: integers, reals, or text (an empty cell is null either way).
OGRFieldType text_field_type(const std::vector<std::string>& cells) {
  bool integers = true, numbers = true;
  for (const auto& c : cells) {
    if (c.empty()) continue;
    long long i = 0;
    const auto [end, ec] = std::from_chars(c.data(), c.data() + c.size(), i);
    integers = integers && ec == std::errc() && end == c.data() + c.size();
    double d = 0.0;
    const auto [dend, dec] = std::from_chars(c.data(), c.data() + c.size(), d);
    numbers = numbers && dec == std::errc() && dend == c.data() + c.size() && std::isfinite(d);
    if (!numbers) return OFTString;
  }
  return integers ? OFTInteger64 : OFTReal;
}

}  // namespace

std::string encode_point_geopackage(const std::string& layer_name, const Eigen::MatrixXd& coords,
                                    const std::vector<PointField>& fields, const std::optional<Crs>& crs) {
  const GdalApi& g = start_gdal();
  register_all_drivers();
  const auto n = static_cast<std::size_t>(coords.rows());
  if (coords.cols() != 2 && coords.cols() != 3) throw Error("encode_point_geopackage: points have 2 or 3 coordinates");
  GDALDriverH driver = g.GDALGetDriverByName("GPKG");
  if (!driver) throw Error("GeoPackage: GDAL has no GPKG driver" + gdal_message());
  const std::string name = vsimem_name(".gpkg");
  std::string bytes;
  {
    Dataset ds(g.GDALCreate(driver, name.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    if (!ds.h) throw Error("GeoPackage: GDAL could not create one" + gdal_message());
    OGRSpatialReferenceH srs = crs ? new_spatial_reference(*crs) : nullptr;
    OGRLayerH layer = g.GDALDatasetCreateLayer(ds.h, layer_name.c_str(), srs, coords.cols() == 3 ? wkbPoint25D : wkbPoint, nullptr);
    if (srs) g.OSRDestroySpatialReference(srs);
    if (!layer) throw Error("GeoPackage: GDAL could not create the layer '" + layer_name + "'" + gdal_message());
    std::vector<OGRFieldType> types;
    for (const auto& f : fields) {
      if ((f.is_text ? f.text.size() : f.numbers.size()) != n)
        throw Error("encode_point_geopackage: field " + f.name + " has another count of values than points");
      types.push_back(f.is_text ? text_field_type(f.text) : OFTReal);
      OGRFieldDefnH fd = g.OGR_Fld_Create(f.name.c_str(), types.back());
      const OGRErr made = g.OGR_L_CreateField(layer, fd, TRUE);
      g.OGR_Fld_Destroy(fd);
      if (made != OGRERR_NONE) throw Error("GeoPackage: GDAL could not create the field '" + f.name + "'" + gdal_message());
    }
    // One transaction: a GeoPackage is SQLite, whose commit per feature made 10,000 points take seconds.
    g.GDALDatasetStartTransaction(ds.h, FALSE);
    OGRFeatureDefnH defn = g.OGR_L_GetLayerDefn(layer);
    for (std::size_t i = 0; i < n; ++i) {
      Feature feature(g.OGR_F_Create(defn));
      const auto row = static_cast<Eigen::Index>(i);
      OGRGeometryH point = g.OGR_G_CreateGeometry(coords.cols() == 3 ? wkbPoint25D : wkbPoint);
      if (coords.cols() == 3) g.OGR_G_SetPoint(point, 0, coords(row, 0), coords(row, 1), coords(row, 2));
      else g.OGR_G_SetPoint_2D(point, 0, coords(row, 0), coords(row, 1));
      g.OGR_F_SetGeometryDirectly(feature.h, point);
      for (std::size_t k = 0; k < fields.size(); ++k) {
        const auto& f = fields[k];
        const int index = static_cast<int>(k);
        if (!f.is_text) {
          if (!std::isnan(f.numbers[i])) g.OGR_F_SetFieldDouble(feature.h, index, f.numbers[i]);
        } else if (!f.text[i].empty()) {
          if (types[k] == OFTString) g.OGR_F_SetFieldString(feature.h, index, f.text[i].c_str());
          else if (types[k] == OFTInteger64) g.OGR_F_SetFieldInteger64(feature.h, index, std::stoll(f.text[i]));
          else g.OGR_F_SetFieldDouble(feature.h, index, std::stod(f.text[i]));
        }
      }
      if (g.OGR_L_CreateFeature(layer, feature.h) != OGRERR_NONE)
        throw Error("GeoPackage: GDAL could not write point " + std::to_string(i) + gdal_message());
    }
    if (g.GDALDatasetCommitTransaction(ds.h) != OGRERR_NONE) throw Error("GeoPackage: GDAL could not commit the points" + gdal_message());
  }  // closed: flushed into the memory file
  return take_memory_file(name);
}

#else  // built without GDAL

namespace {
[[noreturn]] void no_gdal(const std::string& what) {
  throw ArgumentError(what + ": this errfield was built without GDAL (Debian's libgdal-dev), which reads and writes "
                      "vector layers (GeoPackage, shapefile, GeoJSON); install it and build again (scripts/setup.sh), or use CSV");
}
}  // namespace

PointTable read_point_table(const std::string& path, const std::string& option, const RequiredFields&) {
  if (is_vector_path(path)) no_gdal(option + " " + path);
  PointTable p;
  p.table = CsvTable::read(path);
  return p;
}

std::string encode_point_geopackage(const std::string& layer, const Eigen::MatrixXd&, const std::vector<PointField>&,
                                    const std::optional<Crs>&) {
  no_gdal("writing the GeoPackage layer " + layer);
}

#endif

}  // namespace errfield::cli
