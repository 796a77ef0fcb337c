#pragma once
// GDAL, loaded with dlopen the first time a raster, a vector layer or a CRS is used, not linked:
// libgdal pulls in ~100 shared libraries, whose loading made every `errfield` process 0.15-0.2 s
// slower to start (measured: `errfield --help` 0.03 s -> 0.2 s), GIS files or not; the CLI tests
// start it hundreds of times. Included only by the files CMake compiles with GDAL's headers
// (raster_file.cpp, point_layer.cpp, coordinate_system.cpp, gdal_library.cpp), and only when
// ERRFIELD_HAVE_GDAL is defined.

#ifndef ERRFIELD_HAVE_GDAL
#error "gdal_library.hpp needs GDAL's headers (ERRFIELD_HAVE_GDAL)"
#endif

#include <string>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <gdal_frmts.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

namespace errfield::cli::gdal_detail {

// The GDAL functions errfield calls, looked up in the library loaded at run time. Real symbols only:
// CPLFree is a macro for VSIFree, so X(CPLFree) looked up "CPLFree" and failed (VSIFree it is).
#define ERRFIELD_GDAL_FUNCTIONS(X)                                                                            \
  X(CPLSetConfigOption) X(CPLErrorReset) X(CPLGetLastErrorMsg) X(CPLPushErrorHandler) X(CPLQuietErrorHandler) \
  X(VSIFree) X(GDALAllRegister) X(GDALClose) X(GDALOpen) X(GDALOpenEx) X(GDALGetDriverByName) X(GDALCreate)   \
  X(GDALCreateCopy) X(GDALSetGeoTransform) X(GDALGetGeoTransform) X(GDALGetRasterBand) X(GDALGetRasterCount) \
  X(GDALGetRasterXSize) X(GDALGetRasterYSize) X(GDALSetDescription) X(GDALSetRasterNoDataValue)              \
  X(GDALGetRasterNoDataValue) X(GDALRasterIO) X(GDALGetSpatialRef) X(GDALSetSpatialRef) X(VSIGetMemFileBuffer) \
  X(VSIUnlink) X(GDALRegister_GTiff) X(GDALRegister_AAIGrid) X(GDALRegister_MEM)                             \
  X(GDALDatasetGetLayerCount) X(GDALDatasetGetLayer) X(GDALDatasetCreateLayer) X(GDALDatasetStartTransaction) \
  X(GDALDatasetCommitTransaction) X(OGR_L_GetName) X(OGR_L_GetSpatialRef) X(OGR_L_GetLayerDefn)              \
  X(OGR_L_ResetReading) X(OGR_L_GetNextFeature) X(OGR_L_CreateField) X(OGR_L_CreateFeature)                  \
  X(OGR_FD_GetFieldCount) X(OGR_FD_GetFieldDefn) X(OGR_Fld_GetNameRef) X(OGR_Fld_GetType) X(OGR_Fld_Create)  \
  X(OGR_Fld_Destroy) X(OGR_F_Create) X(OGR_F_Destroy) X(OGR_F_GetFID) X(OGR_F_GetGeometryRef)                \
  X(OGR_F_IsFieldSetAndNotNull) X(OGR_F_GetFieldAsDouble) X(OGR_F_GetFieldAsInteger64)                       \
  X(OGR_F_GetFieldAsString) X(OGR_F_SetFieldDouble) X(OGR_F_SetFieldInteger64) X(OGR_F_SetFieldString)        \
  X(OGR_F_SetGeometryDirectly) X(OGR_G_GetGeometryType) X(OGR_G_IsEmpty) X(OGR_G_CreateGeometry)              \
  X(OGR_G_SetPoint) X(OGR_G_SetPoint_2D) X(OGR_G_GetX) X(OGR_G_GetY) X(OGR_G_GetZ) X(OGR_GT_Flatten)         \
  X(OGR_GT_HasZ) X(OGRGeometryTypeToName) X(OSRNewSpatialReference) X(OSRDestroySpatialReference)            \
  X(OSRSetFromUserInput) X(OSRExportToWktEx) X(OSRIsSame) X(OSRGetName) X(OSRGetAuthorityName)                 \
  X(OSRGetAuthorityCode) X(OSRAutoIdentifyEPSG) X(OSRIsGeographic)

struct GdalApi {
#define ERRFIELD_GDAL_POINTER(name) decltype(&::name) name = nullptr;
  ERRFIELD_GDAL_FUNCTIONS(ERRFIELD_GDAL_POINTER)
#undef ERRFIELD_GDAL_POINTER
};

/// GDAL, loaded once per process (the library found by CMake, else its soname), with the raster
/// drivers errfield writes registered; throws Error when it cannot be loaded. Thread-safe.
const GdalApi& gdal();

/// gdal() with the calling thread's last GDAL error cleared (GDAL keeps its errors per thread).
const GdalApi& start_gdal();

/// Registers every GDAL driver, once: the formats errfield only reads (vector layers, any raster
/// format of a covariate), which took ~0.1 s a process to register.
void register_all_drivers();

/// " (GDAL: <last error message>)", or empty when GDAL has none.
std::string gdal_message();

/// A dataset that is closed however the scope is left.
struct Dataset {
  GDALDatasetH h = nullptr;
  explicit Dataset(GDALDatasetH handle) : h(handle) {}
  ~Dataset() { close(); }
  Dataset(const Dataset&) = delete;
  Dataset& operator=(const Dataset&) = delete;
  void close() {
    if (h) gdal().GDALClose(h);
    h = nullptr;
  }
};

/// A unique name in GDAL's in-memory file system ("/vsimem/errfield_<pid>_<n><ext>"): files are
/// written there and committed atomically by the caller.
std::string vsimem_name(const char* ext);

/// The bytes of a /vsimem file, which is then removed. Throws Error when GDAL wrote none.
std::string take_memory_file(const std::string& name);

}  // namespace errfield::cli::gdal_detail

#include <optional>

#include "cli/coordinate_system.hpp"

namespace errfield::cli::gdal_detail {

/// The CRS of a GDAL spatial reference (coordinate_system.cpp).
Crs crs_of(OGRSpatialReferenceH srs);
/// crs_of, or none for a null handle (a dataset or layer without a CRS).
std::optional<Crs> optional_crs_of(OGRSpatialReferenceH srs);
/// A new spatial reference of `crs`, owned by the caller (OSRDestroySpatialReference).
OGRSpatialReferenceH new_spatial_reference(const Crs& crs);

}  // namespace errfield::cli::gdal_detail
