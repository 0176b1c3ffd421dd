// Ground points as tpkit text, GeoJSON (RFC 7946) and CSV with GDAL's sidecars (ground_export.hpp).
#include "tpkit/rpc/ground_export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/version.hpp"

namespace tpkit {
namespace {

using ojson = nlohmann::ordered_json;

std::string lower_extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// "NAME.csv" -> "NAME.EXT" (the sidecars GDAL looks for beside a CSV)
std::string sidecar(const std::string& csv, const std::string& ext) {
  return csv.substr(0, csv.find_last_of('.')) + "." + ext;
}

void check_values(const GroundTable& t, const GroundPoint& p) {
  if (p.values.size() != t.columns.size())
    throw std::invalid_argument("ground point of track " + std::to_string(p.track) + ": " + std::to_string(p.values.size()) +
                                " values for " + std::to_string(t.columns.size()) + " columns");
}

// A property or field value: integers as integers, NaN as null.
ojson json_value(double v, bool integer) {
  if (!std::isfinite(v)) return nullptr;
  if (integer && v == std::floor(v) && std::fabs(v) < 9007199254740992.0) return static_cast<long long>(v);
  return v;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string csv_number(double v, bool integer) {
  if (!std::isfinite(v)) return "";  // GDAL reads an empty field as null
  return integer ? format_id(v) : format_number(v);
}

// Column names of the CSV coordinates: the CRS and the unit in the name (CSV has no comments).
std::vector<std::string> csv_coordinate_names(const GroundConverter& conv) {
  switch (conv.crs()) {
    case GroundCrs::geographic: return {"lon_wgs84_deg", "lat_wgs84_deg", "h_ellipsoid_m"};
    case GroundCrs::utm: {
      const std::string epsg = std::to_string(conv.epsg());
      return {"easting_epsg" + epsg + "_m", "northing_epsg" + epsg + "_m", "h_ellipsoid_m"};
    }
    case GroundCrs::ecef: return {"X_epsg4978_m", "Y_epsg4978_m", "Z_epsg4978_m"};
  }
  return {};
}

// The CRS in WKT with its EPSG code, as GDAL reads a .prj (checked with ogrinfo 3.6). Geographic: WKT2
// (ISO 19162:2019) of EPSG:4979, the 3-D CRS with the ellipsoidal height, which WKT1 cannot express (GDAL
// reports the layer as EPSG:4979, 3D Point). UTM (EPSG:326ZZ/327ZZ) and ECEF (EPSG:4978): WKT1 (OGC
// 01-009, the form GDAL writes in .prj files); UTM's h is named in its column (h_ellipsoid_m).
std::string crs_wkt(const GroundConverter& conv) {
  const std::string datum =
      "DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563,AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],"
      "PRIMEM[\"Greenwich\",0,AUTHORITY[\"EPSG\",\"8901\"]]";
  const std::string geogcs =
      "GEOGCS[\"WGS 84\"," + datum +
      ",UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],AXIS[\"Latitude\",NORTH],AXIS[\"Longitude\",EAST],"
      "AUTHORITY[\"EPSG\",\"4326\"]]";
  switch (conv.crs()) {
    case GroundCrs::geographic:
      return "GEOGCRS[\"WGS 84\",DATUM[\"World Geodetic System 1984\",ELLIPSOID[\"WGS 84\",6378137,298.257223563,"
             "LENGTHUNIT[\"metre\",1]]],PRIMEM[\"Greenwich\",0,ANGLEUNIT[\"degree\",0.0174532925199433]],CS[ellipsoidal,3],"
             "AXIS[\"geodetic latitude (Lat)\",north,ORDER[1],ANGLEUNIT[\"degree\",0.0174532925199433]],"
             "AXIS[\"geodetic longitude (Lon)\",east,ORDER[2],ANGLEUNIT[\"degree\",0.0174532925199433]],"
             "AXIS[\"ellipsoidal height (h)\",up,ORDER[3],LENGTHUNIT[\"metre\",1]],ID[\"EPSG\",4979]]";
    case GroundCrs::utm: {
      const int zone = conv.zone();
      return "PROJCS[\"WGS 84 / UTM zone " + std::to_string(zone) + (conv.north() ? "N" : "S") + "\"," + geogcs +
             ",PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"latitude_of_origin\",0],PARAMETER[\"central_meridian\"," +
             std::to_string(6 * zone - 183) +
             "],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],PARAMETER[\"false_northing\"," +
             (conv.north() ? "0" : "10000000") +
             "],UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"Easting\",EAST],AXIS[\"Northing\",NORTH],"
             "AUTHORITY[\"EPSG\",\"" + std::to_string(conv.epsg()) + "\"]]";
    }
    case GroundCrs::ecef:
      return "GEOCCS[\"WGS 84\"," + datum +
             ",UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"Geocentric X\",OTHER],AXIS[\"Geocentric Y\",OTHER],"
             "AXIS[\"Geocentric Z\",NORTH],AUTHORITY[\"EPSG\",\"4978\"]]";
  }
  return "";
}

Meta with_crs(const GroundTable& t, const GroundConverter& conv) {
  Meta meta = {{"crs", conv.description()}};
  for (const auto& [k, v] : t.meta)
    if (k != "crs") meta.emplace_back(k, v);
  return meta;
}

}  // namespace

GroundForm ground_form_of(const std::string& path) {
  if (path == "-") return GroundForm::tpkit;
  const std::string ext = lower_extension(path);
  if (ext == "geojson" || ext == "json") return GroundForm::geojson;
  if (ext == "csv") return GroundForm::csv;
  return GroundForm::tpkit;
}

std::string ground_form_name(GroundForm form) {
  switch (form) {
    case GroundForm::tpkit: return "tpkit";
    case GroundForm::geojson: return "GeoJSON";
    case GroundForm::csv: return "CSV";
  }
  return "";
}

std::string ground_tpkit_text(const GroundTable& t, const GroundConverter& conv) {
  std::vector<std::string> cols = {"track"};
  for (const auto& c : conv.columns()) cols.push_back(c);
  for (const auto& c : t.columns) cols.push_back(c.name);
  std::ostringstream os;
  write_header(os, "ground", 1, t.images, with_crs(t, conv), cols);
  std::vector<double> rec(4 + t.columns.size());
  for (const auto& p : t.points) {
    check_values(t, p);
    const Eigen::Vector3d c = conv(p.llh, p.track);
    rec[0] = static_cast<double>(p.track);
    for (int k = 0; k < 3; ++k) rec[1 + k] = c[k];
    std::copy(p.values.begin(), p.values.end(), rec.begin() + 4);
    write_record(os, rec);
  }
  for (const auto& [k, v] : t.summary) os << "# " << k << ": " << v << '\n';
  return os.str();
}

std::string ground_geojson_text(const GroundTable& t, const GroundConverter& conv) {
  ojson doc;
  doc["type"] = "FeatureCollection";
  doc["name"] = "tpkit ground points";
  doc["description"] =
      "coordinates [lon, lat, h]: WGS 84 longitude and latitude in degrees, h in metres above the WGS 84 "
      "ellipsoid (EPSG:4979; not a geoid height)";
  ojson head;
  head["kind"] = "ground";
  head["version"] = 1;
  head["written_by"] = written_by();
  head["images"] = ojson::array();
  for (const auto& im : t.images) head["images"].push_back({{"path", im.path}, {"width", im.width}, {"height", im.height}});
  ojson meta = ojson::object();
  for (const auto& [k, v] : t.meta)
    if (k != "crs") meta[k] = v;
  head["meta"] = meta;
  const bool projected = conv.crs() != GroundCrs::geographic;
  std::vector<std::string> proj_names;
  if (projected) {
    proj_names = conv.columns();
    head["projected_crs"] = conv.description();
    head["projected_properties"] = {proj_names[0], proj_names[1], proj_names[2]};
  }
  ojson summary = ojson::object();
  for (const auto& [k, v] : t.summary) summary[k] = v;
  head["summary"] = summary;
  doc["tpkit"] = head;
  ojson features = ojson::array();
  for (const auto& p : t.points) {
    check_values(t, p);
    ojson f;
    f["type"] = "Feature";
    f["id"] = p.track;
    f["geometry"] = {{"type", "Point"}, {"coordinates", {p.llh[0], p.llh[1], p.llh[2]}}};
    ojson props;
    props["track"] = p.track;
    props["h"] = json_value(p.llh[2], false);
    if (projected) {
      const Eigen::Vector3d c = conv(p.llh, p.track);
      for (int k = 0; k < 3; ++k)
        if (!(conv.crs() == GroundCrs::utm && k == 2)) props[proj_names[k]] = c[k];  // UTM's h is h
    }
    for (size_t k = 0; k < t.columns.size(); ++k) props[t.columns[k].name] = json_value(p.values[k], t.columns[k].integer);
    f["properties"] = props;
    features.push_back(std::move(f));
  }
  doc["features"] = std::move(features);
  // a path that is not UTF-8 is written with U+FFFD rather than refused
  return doc.dump(1, ' ', false, ojson::error_handler_t::replace) + "\n";
}

GroundCsv ground_csv_text(const GroundTable& t, const GroundConverter& conv) {
  GroundCsv out;
  std::vector<std::string> names = {"track"};
  std::vector<std::string> types = {"Integer"};
  for (const auto& n : csv_coordinate_names(conv)) names.push_back(n);
  types.insert(types.end(), {"CoordX", "CoordY", "CoordZ"});
  for (const auto& c : t.columns) {
    names.push_back(c.name);
    types.push_back(c.integer ? "Integer" : "Real");
  }
  std::ostringstream os;
  for (size_t k = 0; k < names.size(); ++k) os << (k ? "," : "") << csv_field(names[k]);
  os << '\n';
  for (const auto& p : t.points) {
    check_values(t, p);
    const Eigen::Vector3d c = conv(p.llh, p.track);
    os << format_id(static_cast<double>(p.track));
    for (int k = 0; k < 3; ++k) os << ',' << format_number(c[k]);
    for (size_t k = 0; k < t.columns.size(); ++k) os << ',' << csv_number(p.values[k], t.columns[k].integer);
    os << '\n';
  }
  out.csv = os.str();
  for (size_t k = 0; k < types.size(); ++k) out.csvt += (k ? "," : "") + types[k];
  out.csvt += '\n';
  out.prj = crs_wkt(conv) + "\n";
  return out;
}

std::vector<std::string> ground_output_files(const std::string& path) {
  if (ground_form_of(path) != GroundForm::csv) return {path};
  return {path, sidecar(path, "csvt"), sidecar(path, "prj")};
}

GroundForm write_ground(const std::string& path, const GroundTable& table, const GroundConverter& conv) {
  const GroundForm form = ground_form_of(path);
  switch (form) {
    case GroundForm::tpkit: write_file_atomic(path, ground_tpkit_text(table, conv)); break;
    case GroundForm::geojson: write_file_atomic(path, ground_geojson_text(table, conv)); break;
    case GroundForm::csv: {
      const GroundCsv c = ground_csv_text(table, conv);
      const auto files = ground_output_files(path);
      write_file_atomic(files[0], c.csv);
      write_file_atomic(files[1], c.csvt);
      write_file_atomic(files[2], c.prj);
      break;
    }
  }
  return form;
}

}  // namespace tpkit
