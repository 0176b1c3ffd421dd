// Ground points in three forms, chosen by the output name's extension as ogr2ogr chooses its driver:
//   .geojson, .json   GeoJSON (RFC 7946): a FeatureCollection of Point features, coordinates [lon, lat, h]
//                     in WGS 84 degrees and metres above the WGS 84 ellipsoid (RFC 7946 allows no other
//                     CRS, so none is declared; the top-level "name" and "description" say it, a "tpkit"
//                     foreign member keeps the header: images, metadata, summary). Properties per point:
//                     track, h, the projected coordinates of a --crs other than geographic (easting
//                     northing | X Y Z), and every extra column of the tpkit form. A NaN is null.
//   .csv              CSV with a header line; coordinates in the converter's CRS, named in the column names
//                     (lon_wgs84_deg lat_wgs84_deg h_ellipsoid_m | easting_epsg326ZZ_m northing_epsg326ZZ_m
//                     h_ellipsoid_m | X_epsg4978_m Y_epsg4978_m Z_epsg4978_m), then the extra columns; a NaN
//                     is an empty field. Beside it, as GDAL's CSV driver reads them (GeoCSV): NAME.csvt, the
//                     column types (Integer, Real; CoordX CoordY CoordZ mark the point's coordinates), and
//                     NAME.prj, the CRS in WKT (EPSG:4979 in WKT2, 326ZZ/327ZZ or 4978 in WKT1).
//   anything else, -  the tpkit ground file (tpkit-formats(5)): header, metadata ("# crs:" first), columns
//                     track, the three coordinates, the extra columns; summary lines after the records.
// Numbers are written in the shortest form that reads back to the same double (lon/lat far below 1e-9
// degree). Every file is written through AtomicOutput: a run that fails leaves none of them.
#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "tpkit/core/text_table.hpp"
#include "tpkit/rpc/rpc_ground.hpp"

namespace tpkit {

enum class GroundForm { tpkit, geojson, csv };

// The form of an output name: by its extension, case-insensitive; "-" is the tpkit form.
GroundForm ground_form_of(const std::string& path);
// "tpkit" | "GeoJSON" | "CSV".
std::string ground_form_name(GroundForm form);

// A column after the coordinates (sigma_h, views, rms_px, flagged, ...); integer ones are written as
// JSON integers and typed Integer in the .csvt.
struct GroundColumn {
  std::string name;
  bool integer = false;
};

struct GroundPoint {
  long long track = 0;
  Eigen::Vector3d llh = Eigen::Vector3d::Zero();  // lon, lat (degrees WGS 84), h (m above the ellipsoid)
  std::vector<double> values;                      // one per GroundTable::columns
};

struct GroundTable {
  std::vector<ImageRef> images;
  Meta meta;     // "# key: value" lines after "# crs:" (which the writer sets from the converter)
  std::vector<GroundColumn> columns;
  std::vector<GroundPoint> points;
  Meta summary;  // lines after the records (tpkit form), the "summary" member (GeoJSON); not in the CSV
};

// The texts of each form. The converter gives the tpkit and CSV coordinates (and GeoJSON's projected
// properties); a point it cannot hold is a NumericalError naming its track. A point's values must
// match the columns (std::invalid_argument otherwise).
std::string ground_tpkit_text(const GroundTable& table, const GroundConverter& conv);
std::string ground_geojson_text(const GroundTable& table, const GroundConverter& conv);
struct GroundCsv {
  std::string csv, csvt, prj;
};
GroundCsv ground_csv_text(const GroundTable& table, const GroundConverter& conv);

// The files an output name stands for: the name, and for CSV its .csvt and .prj (for check_outputs).
std::vector<std::string> ground_output_files(const std::string& path);
// Writes `path` in the form of its extension (with the CSV's sidecars), atomically. Returns the form.
GroundForm write_ground(const std::string& path, const GroundTable& table, const GroundConverter& conv);

}  // namespace tpkit
