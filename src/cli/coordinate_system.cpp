// CRSs through GDAL's OSR (coordinate_system.hpp). Compiled on its own with GDAL's headers; without
// GDAL a --crs is refused by name.

#include "cli/coordinate_system.hpp"

#include "errfield/error.hpp"

#ifdef ERRFIELD_HAVE_GDAL
#include "cli/gdal_library.hpp"
#endif

namespace errfield::cli {

void CoordinateSystem::add(const std::optional<Crs>& crs, const std::string& source, const std::string& file) {
  if (!crs) return;
  if (!crs_) {
    crs_ = crs;
    source_ = source;
    return;
  }
  if (same_crs(*crs_, *crs)) return;
  throw InputError("the CRS of " + source + ", " + crs->label + ", differs from the CRS of " + source_ + ", " +
                       crs_->label + "; errfield does not reproject: bring the inputs into one CRS first "
                       "(gdalwarp -t_srs for rasters, ogr2ogr -t_srs for points)",
                   file);
}

std::string CoordinateSystem::geographic_warning() const {
  if (!crs_ || !crs_->geographic) return {};
  return "the coordinates are in " + crs_->label + " (from " + source_ +
         "), latitude and longitude in degrees: distances, radii and variogram ranges are in degrees, not a length; "
         "project the data first (ogr2ogr -t_srs, gdalwarp -t_srs) to work in metres";
}

#ifdef ERRFIELD_HAVE_GDAL

namespace gdal_detail {

// A spatial reference that is destroyed however the scope is left.
struct SpatialReference {
  OGRSpatialReferenceH h;
  SpatialReference() : h(gdal().OSRNewSpatialReference(nullptr)) {}
  ~SpatialReference() {
    if (h) gdal().OSRDestroySpatialReference(h);
  }
  SpatialReference(const SpatialReference&) = delete;
  SpatialReference& operator=(const SpatialReference&) = delete;
};

Crs crs_of(OGRSpatialReferenceH srs) {
  const GdalApi& g = gdal();
  Crs c;
  char* wkt = nullptr;
  const char* options[] = {"FORMAT=WKT2_2019", nullptr};
  if (g.OSRExportToWktEx(srs, &wkt, options) != OGRERR_NONE || !wkt) {
    g.VSIFree(wkt);
    throw Error("GDAL could not write a CRS as WKT" + gdal_message());
  }
  c.wkt = wkt;
  g.VSIFree(wkt);
  c.geographic = g.OSRIsGeographic(srs) != 0;
  // The authority code when the definition has one, else the EPSG code GDAL recognises it as
  // (a copy is identified: identification adds the code to the definition).
  std::string code;
  const char* authority = g.OSRGetAuthorityName(srs, nullptr);
  const char* number = g.OSRGetAuthorityCode(srs, nullptr);
  if (authority && number) {
    code = std::string(authority) + ":" + number;
  } else {
    SpatialReference copy;
    if (copy.h && g.OSRSetFromUserInput(copy.h, c.wkt.c_str()) == OGRERR_NONE && g.OSRAutoIdentifyEPSG(copy.h) == OGRERR_NONE) {
      const char* a = g.OSRGetAuthorityName(copy.h, nullptr);
      const char* n = g.OSRGetAuthorityCode(copy.h, nullptr);
      if (a && n) code = std::string(a) + ":" + n;
    }
    g.CPLErrorReset();
  }
  const char* name = g.OSRGetName(srs);
  const std::string named = name && *name && std::string(name) != "unknown" ? name : "";
  c.label = !code.empty() ? (named.empty() ? code : code + " (" + named + ")") : (named.empty() ? "an unnamed CRS" : "'" + named + "'");
  return c;
}

std::optional<Crs> optional_crs_of(OGRSpatialReferenceH srs) {
  if (!srs) return std::nullopt;
  return crs_of(srs);
}

OGRSpatialReferenceH new_spatial_reference(const Crs& crs) {
  const GdalApi& g = start_gdal();
  OGRSpatialReferenceH h = g.OSRNewSpatialReference(nullptr);
  if (!h || g.OSRSetFromUserInput(h, crs.wkt.c_str()) != OGRERR_NONE) {
    if (h) g.OSRDestroySpatialReference(h);
    throw Error("GDAL could not read back the CRS " + crs.label + gdal_message());
  }
  return h;
}

}  // namespace gdal_detail

Crs parse_crs(const std::string& text, const std::string& option) {
  using namespace gdal_detail;
  const GdalApi& g = start_gdal();
  SpatialReference srs;
  if (text.empty() || !srs.h || g.OSRSetFromUserInput(srs.h, text.c_str()) != OGRERR_NONE)
    throw ArgumentError(option + " is '" + text + "'; expected a CRS GDAL knows: EPSG:NNNN, WKT or a PROJ string" +
                        gdal_message());
  return crs_of(srs.h);
}

bool same_crs(const Crs& a, const Crs& b) {
  using namespace gdal_detail;
  if (a.wkt == b.wkt) return true;
  const GdalApi& g = start_gdal();
  SpatialReference x, y;
  if (!x.h || !y.h || g.OSRSetFromUserInput(x.h, a.wkt.c_str()) != OGRERR_NONE ||
      g.OSRSetFromUserInput(y.h, b.wkt.c_str()) != OGRERR_NONE)
    return false;
  return g.OSRIsSame(x.h, y.h) != 0;
}

#else  // built without GDAL

Crs parse_crs(const std::string&, const std::string& option) {
  throw ArgumentError(option + ": this errfield was built without GDAL (Debian's libgdal-dev), which reads CRSs; "
                      "install it and build again (scripts/setup.sh)");
}

bool same_crs(const Crs& a, const Crs& b) { return a.wkt == b.wkt; }

#endif

}  // namespace errfield::cli
