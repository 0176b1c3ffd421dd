// Ground points in their three forms (ground_export.hpp): the GeoJSON and the CSV parsed back agree
// with the tpkit form to 1e-9; the form follows the extension; a failed write leaves no file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unistd.h>

#include "tpkit/core/text_table.hpp"
#include "tpkit/rpc/ground_export.hpp"

namespace {
using namespace tpkit;
namespace fs = std::filesystem;

GroundTable sample_table() {
  GroundTable t;
  t.images = {{"a.tif", 100, 200}, {"b.tif", 100, 200}};
  t.meta = {{"model1", "a_rpc.txt"}, {"flagged", "1: rms_px above --flag 2 px"}};
  t.columns = {{"sigma_h", false}, {"views", true}, {"rms_px", false}, {"flagged", true}};
  // lon/lat with digits below 1e-9 degree, a NaN sigma, one flagged point
  t.points = {{7, {5.3698123456789012, 43.2965987654321, 152.123456789}, {0.25, 3, 0.0123456789, 0}},
              {12, {5.3712345678901234, 43.2951234567890, 98.5}, {NAN, 2, 2.5, 1}},
              {40, {5.36, 43.29, -12.75}, {1.5e-3, 5, 1e-7, 0}}};
  t.summary = {{"points", "3"}};
  return t;
}

std::vector<std::vector<std::string>> split_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) f.push_back(cell);
    if (!line.empty() && line.back() == ',') f.push_back("");
    rows.push_back(f);
  }
  return rows;
}

TextTable read_tpkit(const std::string& text) {
  std::istringstream in(text);
  ReadOptions opt;
  opt.kind = "ground";
  opt.may_be_missing = [](const std::string& c) { return c == "sigma_h"; };
  return read_table(in, "ground", opt);
}

TEST(GroundExport, FormFollowsTheExtension) {
  EXPECT_EQ(ground_form_of("p.geojson"), GroundForm::geojson);
  EXPECT_EQ(ground_form_of("dir/P.GeoJSON"), GroundForm::geojson);
  EXPECT_EQ(ground_form_of("p.json"), GroundForm::geojson);
  EXPECT_EQ(ground_form_of("p.csv"), GroundForm::csv);
  EXPECT_EQ(ground_form_of("p.CSV"), GroundForm::csv);
  EXPECT_EQ(ground_form_of("p.points"), GroundForm::tpkit);
  EXPECT_EQ(ground_form_of("-"), GroundForm::tpkit);
  EXPECT_EQ(ground_form_of("a.csv/points"), GroundForm::tpkit);  // the folder's dot is no extension
  EXPECT_EQ(ground_output_files("out/g.csv"), (std::vector<std::string>{"out/g.csv", "out/g.csvt", "out/g.prj"}));
  EXPECT_EQ(ground_output_files("g.geojson"), std::vector<std::string>{"g.geojson"});
}

TEST(GroundExport, GeoJsonParsesBackToTheTpkitValues) {
  const GroundTable t = sample_table();
  const GroundConverter conv(GroundCrs::geographic, 5.37, 43.3);
  const TextTable tp = read_tpkit(ground_tpkit_text(t, conv));
  ASSERT_EQ(tp.rows.size(), 3u);
  const auto doc = nlohmann::json::parse(ground_geojson_text(t, conv));
  EXPECT_EQ(doc.at("type"), "FeatureCollection");
  EXPECT_FALSE(doc.contains("crs"));  // RFC 7946: no crs member
  EXPECT_NE(doc.at("description").get<std::string>().find("ellipsoid"), std::string::npos);
  EXPECT_EQ(doc.at("tpkit").at("images").size(), 2u);
  EXPECT_EQ(doc.at("tpkit").at("meta").at("model1"), "a_rpc.txt");
  EXPECT_EQ(doc.at("tpkit").at("summary").at("points"), "3");
  const auto& fs = doc.at("features");
  ASSERT_EQ(fs.size(), 3u);
  for (size_t i = 0; i < fs.size(); ++i) {
    const auto& f = fs[i];
    EXPECT_EQ(f.at("type"), "Feature");
    EXPECT_EQ(f.at("geometry").at("type"), "Point");
    const auto& c = f.at("geometry").at("coordinates");
    ASSERT_EQ(c.size(), 3u);
    EXPECT_NEAR(c[0].get<double>(), tp.rows[i][tp.require("lon")], 1e-9);
    EXPECT_NEAR(c[1].get<double>(), tp.rows[i][tp.require("lat")], 1e-9);
    EXPECT_NEAR(c[2].get<double>(), tp.rows[i][tp.require("h")], 1e-9);
    EXPECT_EQ(c[0].get<double>(), t.points[i].llh[0]);  // full precision: the same double
    EXPECT_EQ(c[1].get<double>(), t.points[i].llh[1]);
    const auto& p = f.at("properties");
    EXPECT_EQ(p.at("track").get<long long>(), static_cast<long long>(tp.rows[i][tp.require("track")]));
    EXPECT_EQ(p.at("h").get<double>(), tp.rows[i][tp.require("h")]);
    EXPECT_TRUE(p.at("views").is_number_integer());
    EXPECT_EQ(p.at("views").get<int>(), static_cast<int>(tp.rows[i][tp.require("views")]));
    EXPECT_EQ(p.at("flagged").get<int>(), static_cast<int>(tp.rows[i][tp.require("flagged")]));
    EXPECT_EQ(p.at("rms_px").get<double>(), tp.rows[i][tp.require("rms_px")]);
    const double s = tp.rows[i][tp.require("sigma_h")];
    if (std::isnan(s))
      EXPECT_TRUE(p.at("sigma_h").is_null());
    else
      EXPECT_EQ(p.at("sigma_h").get<double>(), s);
    EXPECT_FALSE(p.contains("easting"));
  }
  EXPECT_EQ(fs[1].at("properties").at("flagged"), 1);
}

TEST(GroundExport, GeoJsonStaysLonLatWithProjectedProperties) {
  const GroundTable t = sample_table();
  for (GroundCrs crs : {GroundCrs::utm, GroundCrs::ecef}) {
    const GroundConverter conv(crs, 5.37, 43.3);
    const auto doc = nlohmann::json::parse(ground_geojson_text(t, conv));
    const TextTable tp = read_tpkit(ground_tpkit_text(t, conv));
    const auto names = conv.columns();
    for (size_t i = 0; i < t.points.size(); ++i) {
      const auto& f = doc.at("features")[i];
      EXPECT_EQ(f.at("geometry").at("coordinates")[0].get<double>(), t.points[i].llh[0]);
      EXPECT_EQ(f.at("geometry").at("coordinates")[1].get<double>(), t.points[i].llh[1]);
      for (int k = 0; k < 2; ++k)
        EXPECT_NEAR(f.at("properties").at(names[k]).get<double>(), tp.rows[i][tp.require(names[k])], 1e-9) << names[k];
    }
    EXPECT_NE(doc.at("tpkit").at("projected_crs").get<std::string>().find(std::to_string(conv.epsg())), std::string::npos);
  }
}

TEST(GroundExport, CsvHasAHeaderTheValuesAndGdalSidecars) {
  const GroundTable t = sample_table();
  const GroundConverter conv(GroundCrs::geographic, 5.37, 43.3);
  const TextTable tp = read_tpkit(ground_tpkit_text(t, conv));
  const GroundCsv c = ground_csv_text(t, conv);
  const auto rows = split_csv(c.csv);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"track", "lon_wgs84_deg", "lat_wgs84_deg", "h_ellipsoid_m", "sigma_h",
                                               "views", "rms_px", "flagged"}));
  const std::vector<std::string> tp_cols = {"track", "lon", "lat", "h", "sigma_h", "views", "rms_px", "flagged"};
  for (size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), tp_cols.size()) << c.csv;
    for (size_t k = 0; k < tp_cols.size(); ++k) {
      const double want = tp.rows[i - 1][tp.require(tp_cols[k])];
      if (std::isnan(want)) {
        EXPECT_EQ(rows[i][k], "");
      } else {
        EXPECT_NEAR(std::stod(rows[i][k]), want, 1e-9) << tp_cols[k];
        EXPECT_EQ(std::stod(rows[i][k]), want) << tp_cols[k];
      }
    }
  }
  EXPECT_EQ(c.csvt, "Integer,CoordX,CoordY,CoordZ,Real,Integer,Real,Integer\n");
  EXPECT_NE(c.prj.find("ID[\"EPSG\",4979]"), std::string::npos);
  EXPECT_NE(c.prj.find("CS[ellipsoidal,3]"), std::string::npos);

  const GroundConverter utm(GroundCrs::utm, 5.37, 43.3);
  const GroundCsv u = ground_csv_text(t, utm);
  EXPECT_EQ(u.csv.substr(0, u.csv.find('\n')), "track,easting_epsg32631_m,northing_epsg32631_m,h_ellipsoid_m,sigma_h,views,rms_px,flagged");
  EXPECT_NE(u.prj.find("UTM zone 31N"), std::string::npos);
  EXPECT_NE(u.prj.find("AUTHORITY[\"EPSG\",\"32631\"]"), std::string::npos);
  const auto urows = split_csv(u.csv);
  EXPECT_NEAR(std::stod(urows[1][1]), utm(t.points[0].llh)[0], 1e-6);
  const GroundConverter south(GroundCrs::utm, -70.6, -33.4);
  EXPECT_EQ(south.epsg(), 32719);
  EXPECT_NE(ground_csv_text({}, south).prj.find("false_northing\",10000000"), std::string::npos);
  EXPECT_NE(ground_csv_text({}, GroundConverter(GroundCrs::ecef, 0, 0)).csv.find("X_epsg4978_m"), std::string::npos);
}

TEST(GroundExport, TpkitFormKeepsHeaderAndSummary) {
  const GroundTable t = sample_table();
  const std::string text = ground_tpkit_text(t, GroundConverter(GroundCrs::geographic, 0, 0));
  EXPECT_EQ(text.rfind("# tpkit ground 1\n", 0), 0u);
  EXPECT_NE(text.find("# crs: EPSG:4979"), std::string::npos);
  EXPECT_NE(text.find("# columns: track lon lat h sigma_h views rms_px flagged\n"), std::string::npos);
  EXPECT_EQ(text.substr(text.size() - 12), "# points: 3\n");
}

TEST(GroundExport, WritesEveryFileOrNone) {
  const fs::path dir = fs::temp_directory_path() / ("tpkit_ground_export_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const GroundTable t = sample_table();
  const GroundConverter conv(GroundCrs::geographic, 5.37, 43.3);
  EXPECT_EQ(write_ground((dir / "g.csv").string(), t, conv), GroundForm::csv);
  for (const char* f : {"g.csv", "g.csvt", "g.prj"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_EQ(write_ground((dir / "g.geojson").string(), t, conv), GroundForm::geojson);
  std::ifstream in(dir / "g.geojson");
  EXPECT_EQ(nlohmann::json::parse(in).at("features").size(), 3u);
  // a point the CRS cannot hold (UTM far outside its zone): an error, nothing written
  GroundTable bad = t;
  bad.points[1].llh[0] = 120;
  EXPECT_THROW(write_ground((dir / "u.csv").string(), bad, GroundConverter(GroundCrs::utm, 5.37, 43.3)), std::exception);
  EXPECT_FALSE(fs::exists(dir / "u.csv"));
  EXPECT_FALSE(fs::exists(dir / "u.csvt"));
  // values that do not match the columns are refused
  bad = t;
  bad.points[0].values.pop_back();
  EXPECT_THROW(ground_geojson_text(bad, conv), std::invalid_argument);
  fs::remove_all(dir);
}

}  // namespace
