// End-to-end tests of the GIS inputs and outputs (issue 49): CRSs carried from the inputs or
// --crs into rasters and GeoPackages, point layers as samples and targets, --mask. The files are
// made by GDAL's own command-line tools (ogr2ogr, gdal_translate from gdal-bin) and read back by
// GDAL (gdalsrsinfo, and Debian's python3-gdal for every value), not by errfield.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield {
namespace gis_cli_test {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class GisCli : public testing::CliTest {
 protected:
  void SetUp() override {
    if (!ERRFIELD_HAVE_GDAL) GTEST_SKIP() << "built without GDAL (libgdal-dev): GIS files are refused";
    // SIMULATED samples in [0, 50] x [0, 40] (metres of a projected CRS), values rounded to 1e-6
    // so that every format (GeoJSON keeps 15 significant digits) holds them exactly.
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::ostringstream s;
    s.precision(17);
    s << "id,x,y,v\n";
    for (int i = 0; i < 30; ++i) {
      const double x = std::round(50.0 * u(rng) * 1e3) / 1e3, y = std::round(40.0 * u(rng) * 1e3) / 1e3;
      const double v = std::round((std::sin(x / 8.0) + 0.05 * y + 0.2 * u(rng)) * 1e6) / 1e6;
      s << "s" << i << ',' << x << ',' << y << ',' << v << '\n';
    }
    write("S.csv", s.str());
    write("T.csv", "name,x,y\na,5,5\nb,12.5,30\nc,33,17.25\nd,47,39\n");
  }
  // gdal-bin's ogr2ogr: a point layer from a CSV with columns x, y (numbers typed as numbers).
  void points_from_csv(const std::string& csv, const std::string& out, const std::string& srs = "EPSG:27700") const {
    const std::string cmd = "ogr2ogr -q " + (srs.empty() ? std::string() : "-a_srs " + srs + " ") + path(out) + " " + path(csv) +
                            " -oo X_POSSIBLE_NAMES=x -oo Y_POSSIBLE_NAMES=y -oo AUTODETECT_TYPE=YES -oo KEEP_GEOM_COLUMNS=NO"
                            " -nln " + fs::path(out).stem().string() + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  // gdal_translate: a GeoTIFF from an ESRI ASCII grid written here, in `srs`.
  void raster_from_ascii(const std::string& ascii, const std::string& text, const std::string& tif, const std::string& srs) const {
    write(ascii, text);
    const std::string cmd = "gdal_translate -q --config AAIGRID_DATATYPE Float64 -a_srs " + srs + " " + path(ascii) + " " +
                            path(tif) + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  // A program's standard output (with its standard error).
  static std::string capture(const std::string& cmd) {
    FILE* p = ::popen((cmd + " 2>&1").c_str(), "r");
    std::string text;
    char buffer[4096];
    for (std::size_t n; p && (n = std::fread(buffer, 1, sizeof buffer, p)) > 0;) text.append(buffer, n);
    const int status = p ? ::pclose(p) : -1;
    EXPECT_EQ(status, 0) << cmd << "\n" << text;
    return text;
  }
  // gdalsrsinfo's EPSG code of a raster or vector file ("EPSG:27700").
  std::string epsg_of(const std::string& file) const {
    std::string text = capture("gdalsrsinfo -o epsg " + path(file));
    // gdalsrsinfo prints a blank line before the code.
    const auto first = text.find_first_not_of(" \n"), last = text.find_last_not_of(" \n");
    return first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
  }
  // Every raster band or point feature of the files, read by GDAL's Python bindings (numbers as
  // shortest round-trip text): rasters {"srs", "geo", "bands": [{"name", "nodata", "values"}]},
  // layers {"srs", "layer", "features": [{"x", "y", "fields": {...}}]}; "srs" is the EPSG code.
  nlohmann::json read_gis(const std::vector<std::string>& files) const {
    write("dump.py",
          "import json, struct, sys\nfrom osgeo import gdal\ngdal.UseExceptions()\nout = {}\n"
          "def code(srs):\n"
          "    if srs is None: return None\n"
          "    srs.AutoIdentifyEPSG()\n"
          "    return srs.GetAuthorityName(None) + ':' + srs.GetAuthorityCode(None)\n"
          "for f in sys.argv[1:]:\n"
          "    d = gdal.OpenEx(f)\n"
          "    name = f.split('/')[-1]\n"
          "    if d.RasterCount:\n"
          "        bands = []\n"
          "        for b in range(1, d.RasterCount + 1):\n"
          "            band = d.GetRasterBand(b)\n"
          "            bands.append({'name': band.GetDescription(), 'nodata': band.GetNoDataValue(),\n"
          "                          'values': list(struct.unpack('<%dd' % (d.RasterXSize * d.RasterYSize),\n"
          "                              band.ReadRaster(buf_type=gdal.GDT_Float64)))})\n"
          "        out[name] = {'srs': code(d.GetSpatialRef()), 'geo': list(d.GetGeoTransform()), 'bands': bands}\n"
          "    else:\n"
          "        layer = d.GetLayer(0)\n"
          "        feats = []\n"
          "        for ft in layer:\n"
          "            g = ft.GetGeometryRef()\n"
          "            feats.append({'x': g.GetX(), 'y': g.GetY(), 'fields': ft.items()})\n"
          "        out[name] = {'srs': code(layer.GetSpatialRef()), 'layer': layer.GetName(), 'features': feats}\n"
          "print(json.dumps(out))\n");
    std::string args;
    for (const auto& f : files) args += " " + path(f);
    return nlohmann::json::parse(capture("/usr/bin/python3 " + path("dump.py") + args), nullptr, false);
  }
  static constexpr const char* kKriging = "interpolate --method kriging --model \"exp(sill=0.4,range=12)+nug(0.01)\" ";
};

// The same samples as a CSV, a GeoPackage, a shapefile and a GeoJSON file give the same numbers:
// interpolate at targets, cv, variogram and fit-variogram. A layer needs no --coords (its points').
TEST_F(GisCli, PointLayersGiveTheSameResultsAsTheCsv) {
  points_from_csv("S.csv", "S.gpkg");
  points_from_csv("S.csv", "S.shp");
  points_from_csv("S.csv", "S.geojson", "");
  auto r = run(std::string(kKriging) + "--samples " + path("S.csv") + " --targets " + path("T.csv") +
               " --coords x,y --value v --out " + path("P.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  const Eigen::MatrixXd want = CsvTable::read(path("P.csv")).numeric_columns({"pred", "var"});
  for (const std::string layer : {"S.gpkg", "S.shp", "S.geojson"}) {
    r = run(std::string(kKriging) + "--samples " + path(layer) + " --targets " + path("T.csv") + " --value v --out " +
            path(layer + ".csv"));
    ASSERT_EQ(r.exit_code, 0) << layer << r.output();
    const Eigen::MatrixXd got = CsvTable::read(path(layer + ".csv")).numeric_columns({"pred", "var"});
    EXPECT_EQ(got, want) << layer;  // the same numbers in the same order: the same bits
  }
  // cv, variogram and fit-variogram read the layer as they read the CSV.
  const std::string cv = "cv --method kriging --model \"exp(sill=0.4,range=12)+nug(0.01)\" --value v --out ";
  ASSERT_EQ((r = run(cv + path("cv.csv") + " --samples " + path("S.csv") + " --coords x,y")).exit_code, 0) << r.output();
  ASSERT_EQ((r = run(cv + path("cv_gpkg.csv") + " --samples " + path("S.gpkg"))).exit_code, 0) << r.output();
  EXPECT_EQ(CsvTable::read(path("cv_gpkg.csv")).numeric_columns({"pred", "var"}),
            CsvTable::read(path("cv.csv")).numeric_columns({"pred", "var"}));
  const std::string variogram = "variogram --value v --bins 0:30:5 --out ";
  ASSERT_EQ((r = run(variogram + path("g.csv") + " --input " + path("S.csv") + " --coords x,y")).exit_code, 0) << r.output();
  ASSERT_EQ((r = run(variogram + path("g_gpkg.csv") + " --input " + path("S.gpkg"))).exit_code, 0) << r.output();
  EXPECT_EQ(read("g_gpkg.csv"), read("g.csv"));
  const std::string reml = "fit-variogram --method reml --model \"exp(sill=0.4,range=12)+nug(0.01)\" --value v --out ";
  ASSERT_EQ((r = run(reml + path("f.json") + " --input " + path("S.csv") + " --coords x,y")).exit_code, 0) << r.output();
  ASSERT_EQ((r = run(reml + path("f_gpkg.json") + " --input " + path("S.gpkg"))).exit_code, 0) << r.output();
  EXPECT_EQ(nlohmann::json::parse(read("f_gpkg.json")).at("components"), nlohmann::json::parse(read("f.json")).at("components"));
}

// A CRS given with --crs or carried by a point layer is in every raster and GeoPackage written,
// as GDAL reads them back; an ESRI ASCII grid has it in the .prj beside it.
TEST_F(GisCli, CrsRoundTripsThroughGeoTiffAndGeoPackage) {
  points_from_csv("S.csv", "S.gpkg");  // EPSG:27700
  points_from_csv("T.csv", "T.gpkg", "EPSG:27700");
  const std::string csv_samples = std::string(kKriging) + "--samples " + path("S.csv") + " --coords x,y --value v";
  auto r = run(csv_samples + " --crs EPSG:32631 --grid 0:40:10,5:35:10 --out " + path("G.tif"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  EXPECT_THAT(r.out, HasSubstr("in CRS EPSG:32631 (WGS 84 / UTM zone 31N)"));
  EXPECT_EQ(epsg_of("G.tif"), "EPSG:32631");
  // Carried from the samples' layer, with no --crs: raster, ESRI ASCII grid (.prj) and GeoPackage.
  const std::string layer_samples = std::string(kKriging) + "--samples " + path("S.gpkg") + " --value v";
  ASSERT_EQ((r = run(layer_samples + " --grid 0:40:10,5:35:10 --out " + path("L.tif"))).exit_code, 0) << r.output();
  ASSERT_EQ((r = run(layer_samples + " --grid 0:40:10,5:35:10 --out " + path("L.asc"))).exit_code, 0) << r.output();
  EXPECT_THAT(r.out, HasSubstr("with its CRS in " + path("L.prj") + ", " + path("L_var.prj")));
  ASSERT_EQ((r = run(layer_samples + " --targets " + path("T.gpkg") + " --out " + path("P.gpkg"))).exit_code, 0) << r.output();
  EXPECT_THAT(r.out, HasSubstr("wrote GeoPackage " + path("P.gpkg") + " (layer 'P', 4 points) in CRS EPSG:27700"));
  // CSV targets, the same predictions, in the CRS of --crs.
  ASSERT_EQ((r = run(csv_samples + " --crs EPSG:27700 --targets " + path("T.csv") + " --out " + path("Q.gpkg"))).exit_code, 0)
      << r.output();
  ASSERT_EQ((r = run(csv_samples + " --targets " + path("T.csv") + " --out " + path("Q.csv"))).exit_code, 0) << r.output();
  for (const char* f : {"L.tif", "L.asc", "P.gpkg", "Q.gpkg"}) EXPECT_EQ(epsg_of(f), "EPSG:27700") << f;

  const nlohmann::json got = read_gis({"G.tif", "L.tif", "P.gpkg", "Q.gpkg"});
  ASSERT_TRUE(got.is_object()) << got;
  EXPECT_EQ(got.at("G.tif").at("srs"), "EPSG:32631");
  EXPECT_EQ(got.at("L.tif").at("srs"), "EPSG:27700");
  // The same kriging at the same nodes: the CRS changes nothing else.
  EXPECT_EQ(got.at("L.tif").at("bands"), got.at("G.tif").at("bands"));
  const CsvTable q = CsvTable::read(path("Q.csv"));
  for (const char* f : {"P.gpkg", "Q.gpkg"}) {
    const auto& layer = got.at(f);
    EXPECT_EQ(layer.at("srs"), "EPSG:27700") << f;
    ASSERT_EQ(layer.at("features").size(), q.row_count()) << f;
    for (std::size_t i = 0; i < q.row_count(); ++i) {
      const auto& feature = layer.at("features")[i];
      EXPECT_EQ(feature.at("x").get<double>(), q.numeric_column("x")[i]) << f;
      EXPECT_EQ(feature.at("y").get<double>(), q.numeric_column("y")[i]) << f;
      EXPECT_EQ(feature.at("fields").at("name"), q.row(i)[0]) << f;
      EXPECT_EQ(feature.at("fields").at("pred").get<double>(), q.numeric_column("pred")[i]) << f;
      EXPECT_EQ(feature.at("fields").at("var").get<double>(), q.numeric_column("var")[i]) << f;
      EXPECT_FALSE(feature.at("fields").contains("x")) << f;  // the geometry holds the coordinates
    }
  }
}

// Inputs in different CRSs are refused, naming both; nothing is written.
TEST_F(GisCli, InputsInDifferentCrssAreRefusedNamingBoth) {
  points_from_csv("S.csv", "S.gpkg");  // EPSG:27700
  points_from_csv("T.csv", "T4326.gpkg", "EPSG:4326");
  const std::string layer_samples = std::string(kKriging) + "--samples " + path("S.gpkg") + " --value v";
  auto r = run(layer_samples + " --crs EPSG:32631 --grid 0:40:10,5:35:10 --out " + path("X.tif"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("the CRS of --samples " + path("S.gpkg") + ", EPSG:27700 (OSGB36 / British National Grid), "
                               "differs from the CRS of --crs, EPSG:32631 (WGS 84 / UTM zone 31N)"));
  r = run(layer_samples + " --targets " + path("T4326.gpkg") + " --out " + path("X.gpkg"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("the CRS of --targets " + path("T4326.gpkg") + ", EPSG:4326 (WGS 84), differs from the CRS of "
                               "--samples " + path("S.gpkg")));
  // A covariate raster and a mask in another CRS.
  std::string grid = "ncols 12\nnrows 10\nxllcorner -5\nyllcorner -5\ncellsize 5\n";
  for (int row = 0; row < 10; ++row) grid += "1 2 3 4 5 6 7 8 9 10 11 12\n";
  raster_from_ascii("c.asc", grid, "c.tif", "EPSG:3857");
  r = run(layer_samples + " --covariates c=" + path("c.tif") + " --grid 0:40:10,5:35:10 --out " + path("X.tif"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("the CRS of covariate raster " + path("c.tif") + ", EPSG:3857 (WGS 84 / Pseudo-Mercator)"));
  r = run(layer_samples + " --mask " + path("c.tif") + " --grid 0:40:10,5:35:10 --out " + path("X.tif"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("the CRS of --mask " + path("c.tif") + ", EPSG:3857"));
  r = run(layer_samples + " --crs EPSG:999999 --grid 0:40:10,5:35:10 --out " + path("X.tif"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--crs is 'EPSG:999999'; expected a CRS GDAL knows"));
  // The residual variogram checks its covariate raster against the layer too.
  r = run("variogram --input " + path("S.gpkg") + " --value v --bins 0:30:10 --covariates c=" + path("c.tif") + " --out " +
          path("X.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("differs from the CRS of --input " + path("S.gpkg")));
  for (const char* f : {"X.tif", "X.gpkg", "X.csv"}) EXPECT_FALSE(fs::exists(path(f))) << f;
}

// --mask: the nodes on a nodata pixel of the mask, or outside it, are nodata; the others hold what
// the unmasked grid holds there.
TEST_F(GisCli, MaskPredictsOnlyWhereTheRasterHasData) {
  // 10 x 8 pixels of 5 x 5 from (-2.5, -2.5): pixel (col, row) is nodata where col + row < 4 or
  // col > 7 (an irregular footprint); the grid's nodes x = 0..50 step 5 reach past it (col 10).
  std::string mask = "ncols 10\nnrows 8\nxllcorner -2.5\nyllcorner -2.5\ncellsize 5\nNODATA_value -1\n";
  auto has_data = [](int col, int row) { return col < 10 && row >= 0 && row < 8 && !(col + row < 4 || col > 7); };
  for (int row = 0; row < 8; ++row) {
    for (int col = 0; col < 10; ++col) mask += std::string(col ? " " : "") + (has_data(col, row) ? "1" : "-1");
    mask += "\n";
  }
  raster_from_ascii("mask.asc", mask, "mask.tif", "EPSG:27700");
  const std::string base = std::string(kKriging) + "--samples " + path("S.csv") + " --coords x,y --value v --grid 0:50:5,0:35:5";
  auto r = run(base + " --out " + path("all.tif"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  r = run(base + " --mask " + path("mask.tif") + " --out " + path("masked.tif"));
  ASSERT_EQ(r.exit_code, 0) << r.output();
  ASSERT_EQ((r = run(base + " --mask " + path("mask.tif") + " --out " + path("masked.csv"))).exit_code, 0) << r.output();
  // Nodes: 11 x 8; node (i, j) at x = 5i, y = 35 - 5j (raster row j) lies in mask pixel (i, j).
  std::size_t inside = 0;
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 11; ++i) inside += has_data(i, j) ? 1 : 0;
  EXPECT_THAT(r.out, HasSubstr(std::to_string(inside) + " predicted, " + std::to_string(88 - inside) + " outside --mask"));
  const nlohmann::json got = read_gis({"all.tif", "masked.tif"});
  ASSERT_TRUE(got.is_object()) << got;
  EXPECT_EQ(got.at("masked.tif").at("srs"), "EPSG:27700");  // carried from the mask
  const CsvTable csv = CsvTable::read(path("masked.csv"));
  ASSERT_EQ(csv.row_count(), 88u);
  for (std::size_t b = 0; b < 2; ++b) {
    const auto all = got.at("all.tif").at("bands")[b].at("values").get<std::vector<double>>();
    const auto masked = got.at("masked.tif").at("bands")[b].at("values").get<std::vector<double>>();
    ASSERT_EQ(masked.size(), 88u);
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 11; ++i) {
        const auto k = static_cast<std::size_t>(j * 11 + i);
        if (has_data(i, j)) {
          // Kriging at fewer targets: the same system per target, the same value to the last bits.
          EXPECT_DOUBLE_EQ(masked[k], all[k]) << i << "," << j;
          EXPECT_DOUBLE_EQ(csv.numeric_cell(k, csv.column_index(b == 0 ? "pred" : "var")), all[k]) << i << "," << j;
        } else {
          EXPECT_EQ(masked[k], -9999.0) << i << "," << j;
          EXPECT_EQ(csv.cell(k, csv.column_index(b == 0 ? "pred" : "var")), "") << i << "," << j;
        }
      }
  }
  // A mask that misses the grid, and a mask without --grid, are refused.
  r = run(std::string(kKriging) + "--samples " + path("S.csv") + " --coords x,y --value v --grid 100:120:5,100:120:5 --mask " +
          path("mask.tif") + " --out " + path("none.tif"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("none of the 25 nodes of --grid 100:120:5,100:120:5 falls on a pixel with data"));
  r = run(std::string(kKriging) + "--samples " + path("S.csv") + " --coords x,y --value v --targets " + path("T.csv") +
          " --mask " + path("mask.tif") + " --out " + path("none.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--mask " + path("mask.tif") + " restricts the nodes of --grid"));
}

// A layer errfield cannot use is refused naming the file, the layer, the feature and the field.
TEST_F(GisCli, BadLayersAreRefusedNamingLayerFeatureAndField) {
  auto geojson = [](const std::string& features) {
    return "{\"type\": \"FeatureCollection\", \"name\": \"pts\", \"features\": [" + features + "]}";
  };
  auto point = [](int id, double x, double y, const std::string& v) {
    return "{\"type\": \"Feature\", \"id\": " + std::to_string(id) + ", \"properties\": {\"v\": " + v +
           ", \"label\": \"p\"}, \"geometry\": {\"type\": \"Point\", \"coordinates\": [" + format_number(x) + ", " +
           format_number(y) + "]}}";
  };
  const std::string line = "{\"type\": \"Feature\", \"id\": 7, \"properties\": {\"v\": 1, \"label\": \"l\"}, \"geometry\": "
                           "{\"type\": \"LineString\", \"coordinates\": [[0, 0], [1, 1]]}}";
  write("line.geojson", geojson(point(1, 0, 0, "1.5") + ", " + point(2, 5, 5, "2") + ", " + line));
  write("null.geojson", geojson(point(1, 0, 0, "1.5") + ", " + point(4, 5, 5, "null") + ", " + point(5, 9, 1, "3")));
  write("ok.geojson", geojson(point(1, 0, 0, "1.5") + ", " + point(2, 5, 5, "2") + ", " + point(3, 9, 1, "3")));
  const std::string idw = "interpolate --method idw --targets " + path("T.csv") + " --out " + path("X.csv") + " --samples ";
  auto r = run(idw + path("line.geojson") + " --value v");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr(path("line.geojson") + ", layer 'pts', feature FID 7: the geometry is a Line String; expected a Point"));
  r = run(idw + path("null.geojson") + " --value v");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr(path("null.geojson") + ", layer 'pts', feature FID 4: field 'v' is null; expected a number"));
  r = run(idw + path("ok.geojson") + " --value zinc");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr(path("ok.geojson") + ", layer 'pts': has no field 'zinc'; its fields: v, label"));
  r = run(idw + path("ok.geojson") + " --value label");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("field 'label' holds text, not numbers"));
  // A CSV still needs --coords; a good layer works.
  r = run(idw + path("S.csv") + " --value v");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("is a CSV: give its coordinate columns with --coords"));
  EXPECT_FALSE(fs::exists(path("X.csv")));
  r = run(idw + path("ok.geojson") + " --value v");
  EXPECT_EQ(r.exit_code, 0) << r.output();
}

}  // namespace gis_cli_test
}  // namespace errfield
