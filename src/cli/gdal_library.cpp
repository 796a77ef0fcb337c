// GDAL loaded at run time (gdal_library.hpp says why). Compiled only with GDAL's headers.

#ifdef ERRFIELD_HAVE_GDAL

#include "cli/gdal_library.hpp"

#include <atomic>
#include <mutex>

#include <dlfcn.h>
#include <unistd.h>

#include "errfield/error.hpp"

namespace errfield::cli::gdal_detail {

const GdalApi& gdal() {
  static const GdalApi api = [] {
    void* handle = nullptr;
    std::string tried;
    for (const char* name : {ERRFIELD_GDAL_LIBRARY, "libgdal.so", "libgdal.so.32"}) {
      handle = ::dlopen(name, RTLD_NOW | RTLD_LOCAL);
      if (handle) break;
      const char* why = ::dlerror();
      tried += std::string(tried.empty() ? "" : "; ") + (why ? why : name);
    }
    if (!handle) throw Error("GDAL: cannot load it (" + tried + "); install Debian's libgdal-dev (scripts/setup.sh)");
    GdalApi a;
#define ERRFIELD_GDAL_LOOKUP(name)                                                              \
  a.name = reinterpret_cast<decltype(&::name)>(::dlsym(handle, #name));                          \
  if (!a.name) throw Error(std::string("GDAL: the library has no function ") + #name);
    ERRFIELD_GDAL_FUNCTIONS(ERRFIELD_GDAL_LOOKUP)
#undef ERRFIELD_GDAL_LOOKUP
    // Errors come back as messages in errfield's own words, not printed by GDAL on stderr.
    a.CPLPushErrorHandler(a.CPLQuietErrorHandler);
    // No .aux.xml side files: the files errfield writes are the whole output.
    a.CPLSetConfigOption("GDAL_PAM_ENABLED", "NO");
    // GDAL reads an ESRI ASCII grid of decimals as Float32 unless told: a covariate would lose digits.
    a.CPLSetConfigOption("AAIGRID_DATATYPE", "Float64");
    // The three raster drivers errfield writes with; all others only when a file needs one
    // (register_all_drivers): registering every driver took ~0.1 s a process.
    a.GDALRegister_MEM();
    a.GDALRegister_GTiff();
    a.GDALRegister_AAIGrid();
    return a;
  }();
  return api;
}

const GdalApi& start_gdal() {
  const GdalApi& g = gdal();
  g.CPLErrorReset();
  return g;
}

void register_all_drivers() {
  static std::once_flag all;
  std::call_once(all, [] { gdal().GDALAllRegister(); });
  gdal().CPLErrorReset();
}

std::string gdal_message() {
  const char* m = gdal().CPLGetLastErrorMsg();
  return m && *m ? std::string(" (GDAL: ") + m + ")" : std::string();
}

std::string vsimem_name(const char* ext) {
  static std::atomic<unsigned> counter{0};
  return "/vsimem/errfield_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ext;
}

std::string take_memory_file(const std::string& name) {
  vsi_l_offset length = 0;
  GByte* data = gdal().VSIGetMemFileBuffer(name.c_str(), &length, FALSE);
  if (!data) throw Error("GDAL wrote no " + name + gdal_message());
  std::string bytes(reinterpret_cast<const char*>(data), static_cast<std::size_t>(length));
  gdal().VSIUnlink(name.c_str());
  return bytes;
}

}  // namespace errfield::cli::gdal_detail

#endif
