// The RPC forms of issue 26 beside the vendors' ones: OSSIM .geom keyword lists (ossimRpcModel, read and
// written; ossimPleiadesModel, polynomial_format A), GDAL's .aux.xml RPC metadata domain (read and written)
// and DIMAP v1 (Pléiades' PHRDIMAP.XML, read). Each: write -> read is exact, its pixel convention is pinned
// by a model written by hand in that form and compared with the same model in txt form, malformed and
// truncated files are refused with file:line, and the sidecars are found beside an image.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_model.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("tpkit-rpc-forms-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d / name;
}
const std::string kData = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille";

void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// The error message of reading `p` (by its name's form), "" if it reads.
std::string error_of(const fs::path& p) {
  try {
    read_rpc_file(p.string());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A model whose every number is arbitrary (no short decimal), with a direct model.
RpcModel arbitrary_model() {
  RpcModel m;
  m.err_bias = 0.1;
  m.err_rand = 1.0 / 3;
  m.line_off = 4095.5;
  m.samp_off = 2047.5;
  m.lat_off = 43.3;
  m.lon_off = 5.4;
  m.height_off = 100.25;
  m.line_scale = 4096.5;
  m.samp_scale = 4096;
  m.lat_scale = 0.0123456789;
  m.lon_scale = 0.0234567891;
  m.height_scale = 500;
  for (int i = 0; i < 20; ++i) {
    m.line_num[i] = std::sin(i + 1.0) * std::pow(10.0, -i % 7);
    m.samp_num[i] = std::cos(i + 2.0) * 1e-3 / (i + 1);
    m.line_den[i] = i ? 1e-7 * std::sin(3.0 * i) : 1;
    m.samp_den[i] = i ? -1e-9 * i : 1;
    m.lon_num[i] = 1e-5 * i + 0.1;
    m.lat_num[i] = -1e-6 * i + (i == 2 ? 0.9 : 0);
    m.lon_den[i] = m.lat_den[i] = i ? 1e-9 * std::cos(i * 1.0) : 1;
  }
  m.has_direct = true;
  return m;
}

// The model pinned in every form: x = SAMP_OFF + SAMP_SCALE * (L + H / 100), y = LINE_OFF - LINE_SCALE * P,
// so that ground (LONG_OFF, LAT_OFF, HEIGHT_OFF) projects to (SAMP_OFF, LINE_OFF) in the form's convention.
RpcModel pinned_model() {
  RpcModel m;
  m.samp_off = 20, m.line_off = 10, m.lat_off = 43, m.lon_off = 5, m.height_off = 0;
  m.samp_scale = m.line_scale = 1000;
  m.lat_scale = m.lon_scale = 0.01;
  m.height_scale = 100;
  m.samp_num[1] = 1;
  m.samp_num[3] = 0.01;
  m.line_num[2] = -1;
  m.samp_den[0] = m.line_den[0] = 1;
  return m;
}

// The pinned model's 80 coefficients as "NAME<sep>VALUE" lines, NAME = name(poly, term): written here
// term by term, not by tpkit's writers.
std::string pinned_coefficients(const std::function<std::string(const std::string& poly, int term)>& name,
                                const std::string& sep) {
  const RpcModel m = pinned_model();
  const std::pair<const char*, const RpcPoly*> polys[] = {
      {"line_num", &m.line_num}, {"line_den", &m.line_den}, {"samp_num", &m.samp_num}, {"samp_den", &m.samp_den}};
  std::string out;
  for (const auto& [poly, p] : polys)
    for (int t = 0; t < 20; ++t) out += name(poly, t) + sep + ((*p)[t] == 0 ? "0" : format_number((*p)[t])) + "\n";
  return out;
}

// The pinned model in txt form, hand-written: the reference every other form is compared with.
RpcModel pinned_from_txt() {
  std::string txt =
      "LINE_OFF: 10\nSAMP_OFF: 20\nLAT_OFF: 43\nLONG_OFF: 5\nHEIGHT_OFF: 0\nLINE_SCALE: 1000\nSAMP_SCALE: 1000\n"
      "LAT_SCALE: 0.01\nLONG_SCALE: 0.01\nHEIGHT_SCALE: 100\n";
  txt += pinned_coefficients(
      [](const std::string& poly, int t) {
        std::string up = poly;
        for (auto& c : up) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        return up + "_COEFF_" + std::to_string(t + 1);
      },
      ": ");
  auto p = scratch("pinned_rpc.txt");
  write(p, txt);
  RpcModel m = read_rpc_txt(p.string());
  EXPECT_EQ(m, pinned_model());
  return m;
}

// An OSSIM keyword list of the pinned model as OTB writes an ossimPleiadesModel (two blanks after the
// colon, support_data. and adjustment keys, a """ value), written by hand.
std::string pinned_geom(const std::string& type = "ossimPleiadesModel", const std::string& extra = "") {
  std::string g = "adjustment_0.adj_param_0.center:  0\nadjustment_0.adj_param_0.description:  intrack_offset\n"
                  "bias_error:  0\nheight_off:  0\nheight_scale:  100\nimage_id:  PRG_FC_1\nlat_off:  43\n"
                  "lat_scale:  0.01\n";
  g += pinned_coefficients(
      [](const std::string& poly, int t) {
        char k[32];
        std::snprintf(k, sizeof k, "%s_coeff_%02d", poly.c_str(), t);
        return std::string(k);
      },
      ":  ");
  g += "line_off:  10\nline_scale:  1000\nlong_off:  5\nlong_scale:  0.01\npolynomial_format:  B\nrand_error:  0\n"
       "rect:  0 0 39999 22939\nsamp_off:  20\nsamp_scale:  1000\nsensor:  PHR 1B\n"
       "support_data.band_name_list:  \"\"\"P \"\"\"\nsupport_data.processing_level:  SENSOR\n"
       "support_data.azimuth_angle:  \"\"\"164.87 164.86\n164.85 \"\"\"\n"
       "// a comment, as OSSIM's templates write them\n"
       "type:  " + type + "\n" + extra;
  return g;
}

// An .aux.xml of the pinned model as GDAL writes one (other metadata around the RPC domain; each
// polynomial's coefficients in one value with a trailing blank), written by hand.
std::string pinned_aux(const std::string& extra = "") {
  const RpcModel m = pinned_model();
  auto list = [](const RpcPoly& p) {
    std::string s;
    for (double c : p) s += (c == 0 ? std::string("0") : format_number(c)) + " ";
    return s;
  };
  return "<PAMDataset>\n  <Metadata>\n    <MDI key=\"NITF_IC\">NC</MDI>\n    <MDI key=\"NITF_FSCATP\"></MDI>\n"
         "  </Metadata>\n  <Metadata domain=\"RPC\">\n    <MDI key=\"ERR_BIAS\">0</MDI>\n"
         "    <MDI key=\"HEIGHT_OFF\">0</MDI>\n    <MDI key=\"HEIGHT_SCALE\">100</MDI>\n"
         "    <MDI key=\"LAT_OFF\">43</MDI>\n    <MDI key=\"LAT_SCALE\">0.01</MDI>\n"
         "    <MDI key=\"LINE_DEN_COEFF\">" + list(m.line_den) + "</MDI>\n"
         "    <MDI key=\"LINE_NUM_COEFF\">" + list(m.line_num) + "</MDI>\n"
         "    <MDI key=\"LINE_OFF\">10</MDI>\n    <MDI key=\"LINE_SCALE\">1000</MDI>\n"
         "    <MDI key=\"LONG_OFF\">5</MDI>\n    <MDI key=\"LONG_SCALE\">0.01</MDI>\n"
         "    <MDI key=\"MAX_LAT\">43.01</MDI>\n    <MDI key=\"MIN_LONG\">4.99</MDI>\n"
         "    <MDI key=\"SAMP_DEN_COEFF\">" + list(m.samp_den) + "</MDI>\n"
         "    <MDI key=\"SAMP_NUM_COEFF\">" + list(m.samp_num) + "</MDI>\n"
         "    <MDI key=\"SAMP_OFF\">20</MDI>\n    <MDI key=\"SAMP_SCALE\">1000</MDI>\n" + extra +
         "  </Metadata>\n  <PAMRasterBand band=\"1\">\n    <Metadata>\n"
         "      <MDI key=\"STATISTICS_MAXIMUM\">2047</MDI>\n    </Metadata>\n  </PAMRasterBand>\n</PAMDataset>\n";
}

// A DIMAP v1 document (PHRDIMAP.XML) of a model with a direct model, as CNES shareloc reads one: 40 numbers
// per rational function, A = scale and B = offset of Lon, Lat, Alt, Col, Row, pixels numbered from 1
// (Col.B = SAMP_OFF + 1, written exactly for offsets whose + 1 is exact).
std::string dimap_v1(const RpcModel& m) {
  auto f = [](const RpcPoly& num, const RpcPoly& den) {
    std::string s;
    for (double c : num) s += format_number(c) + " ";
    for (int i = 0; i < 20; ++i) s += format_number(den[i]) + (i < 19 ? " " : "");
    return s;
  };
  auto ab = [](const char* axis, double a, double b) {
    return std::string("          <") + axis + ">\n            <A>" + format_number(a) + "</A>\n            <B>" +
           format_number(b) + "</B>\n          </" + axis + ">\n";
  };
  return "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n<PHR_Dimap_Document>\n"
         "  <Metadata_Identification>\n    <METADATA_PROFILE version=\"1.4\">PHR_SYSTEM_RECTIFIED_PRODUCT</METADATA_PROFILE>\n"
         "    <METADATA_FORMAT>DIMAP_PHR</METADATA_FORMAT>\n  </Metadata_Identification>\n  <Geoposition>\n"
         "    <Rational_Sensor_Model>\n      <Global_RFM>\n        <Direct_Model>\n          <F_LON>" +
         f(m.lon_num, m.lon_den) + "</F_LON>\n          <F_LAT>" + f(m.lat_num, m.lat_den) +
         "</F_LAT>\n          <MODEL_PRECISION_X>0.0002</MODEL_PRECISION_X>\n        </Direct_Model>\n"
         "        <Inverse_Model>\n          <F_COL>" + f(m.samp_num, m.samp_den) + "</F_COL>\n          <F_ROW>" +
         f(m.line_num, m.line_den) + "</F_ROW>\n        </Inverse_Model>\n        <RFM_Validity>\n" +
         "          <Direct_Model_Validity_Domain>\n            <FIRST_ROW>1</FIRST_ROW>\n            <FIRST_COL>1</FIRST_COL>\n"
         "          </Direct_Model_Validity_Domain>\n" +
         ab("Lon", m.lon_scale, m.lon_off) + ab("Lat", m.lat_scale, m.lat_off) + ab("Alt", m.height_scale, m.height_off) +
         ab("Col", m.samp_scale, m.samp_off + 1) + ab("Row", m.line_scale, m.line_off + 1) +
         "        </RFM_Validity>\n      </Global_RFM>\n    </Rational_Sensor_Model>\n  </Geoposition>\n"
         "  <Product_Frame>\n    <PIXEL_ORIGIN>1</PIXEL_ORIGIN>\n  </Product_Frame>\n</PHR_Dimap_Document>\n";
}

void expect_error(const fs::path& p, const std::string& text, const std::string& what) {
  write(p, text);
  const std::string e = error_of(p);
  EXPECT_NE(e.find(what), std::string::npos) << "expected '" << what << "', got '" << e << "'";
}
}  // namespace

TEST(RpcForms, GeomAndAuxRoundTripExactly) {
  std::vector<RpcModel> models = {arbitrary_model(), pinned_model()};
  if (fs::exists(kData + "/img_01.tif")) models.push_back(*read_rpc_tiff(kData + "/img_01.tif"));
  for (RpcModel m : models) {
    m.has_direct = false;  // neither form carries a direct model
    m.lon_num = m.lon_den = m.lat_num = m.lat_den = RpcPoly{};
    for (const char* name : {"m.geom", "m.tif.aux.xml"}) {
      auto p = scratch(name).string();
      write_rpc_file(p, rpc_form_of(p), m);
      const RpcModel r = read_rpc_file(p);
      EXPECT_EQ(r, m) << name;
      std::ifstream in(p);
      const std::string first((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      write_rpc_file(p, rpc_form_of(p), r);
      std::ifstream again(p);
      EXPECT_EQ(std::string((std::istreambuf_iterator<char>(again)), std::istreambuf_iterator<char>()), first) << name;
    }
  }
  // the .geom is one "key: value" per line (shareloc splits each line at ": " into exactly two parts)
  std::istringstream lines(format_rpc_geom(pinned_model()));
  std::string line;
  int n = 0;
  while (std::getline(lines, line)) {
    ++n;
    const size_t at = line.find(": ");
    ASSERT_NE(at, std::string::npos) << line;
    EXPECT_EQ(line.find(": ", at + 1), std::string::npos) << line;
  }
  EXPECT_EQ(n, 2 + 12 + 80);
  EXPECT_NE(format_rpc_geom(pinned_model()).find("type: ossimRpcModel\n"), std::string::npos);
  EXPECT_NE(format_rpc_geom(pinned_model()).find("polynomial_format: B\n"), std::string::npos);
}

// OSSIM's image space has (0, 0) at the centre of the top-left pixel, as RPC00B: a .geom's samp_off and
// line_off are tpkit's as they are.
TEST(RpcForms, GeomPixelsAreRpc00bs) {
  const RpcModel txt = pinned_from_txt();
  auto p = scratch("pinned.geom");
  write(p, pinned_geom());
  const RpcModel g = read_rpc_geom(p.string());
  EXPECT_EQ(g, txt);
  const Eigen::Vector2d q = g.project(5, 43, 0);
  EXPECT_EQ(q[0], 20);
  EXPECT_EQ(q[1], 10);
  EXPECT_EQ(g.project(5.001, 42.999, 50), txt.project(5.001, 42.999, 50));
  // the same model as an ossimRpcModel, and as OSSIM's NITF model
  for (const char* type : {"ossimRpcModel", "ossimNitfRpcModel", "ossimSpot6Model"}) {
    write(p, pinned_geom(type));
    EXPECT_EQ(read_rpc_geom(p.string()), txt) << type;
  }
}

// polynomial_format A: RPC00A's term order 1 L P H LP LH PH LPH L2 P2 H2 L3 L2P L2H LP2 P3 P2H LH2 PH2 H3
// (OSSIM ossimRpcModel::polynomial), reordered to RPC00B's when read.
TEST(RpcForms, GeomPolynomialFormatAIsReordered) {
  const RpcModel m = arbitrary_model();
  // the term order of each format as monomial exponents (L, P, H)
  const int b[20][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1},
                        {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {1, 1, 1}, {3, 0, 0}, {1, 2, 0}, {1, 0, 2},
                        {2, 1, 0}, {0, 3, 0}, {0, 1, 2}, {2, 0, 1}, {0, 2, 1}, {0, 0, 3}};
  const int a[20][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1},
                        {1, 1, 1}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, {3, 0, 0}, {2, 1, 0}, {2, 0, 1},
                        {1, 2, 0}, {0, 3, 0}, {0, 2, 1}, {1, 0, 2}, {0, 1, 2}, {0, 0, 3}};
  std::string text = format_rpc_geom(m);
  text = std::regex_replace(text, std::regex("polynomial_format: B"), "polynomial_format: A");
  const std::pair<const char*, const RpcPoly*> polys[] = {
      {"line_num", &m.line_num}, {"line_den", &m.line_den}, {"samp_num", &m.samp_num}, {"samp_den", &m.samp_den}};
  for (const auto& [poly, p] : polys)
    for (int ia = 0; ia < 20; ++ia) {
      int ib = 0;
      while (b[ib][0] != a[ia][0] || b[ib][1] != a[ia][1] || b[ib][2] != a[ia][2]) ++ib;
      char key[32];
      std::snprintf(key, sizeof key, "%s_coeff_%02d: ", poly, ia);
      text = std::regex_replace(text, std::regex(std::string(key) + "[^\n]*"), key + format_number((*p)[ib]));
    }
  auto path = scratch("format_a.geom");
  write(path, text);
  RpcModel expected = m;
  expected.has_direct = false;
  expected.lon_num = expected.lon_den = expected.lat_num = expected.lat_den = RpcPoly{};
  EXPECT_EQ(read_rpc_geom(path.string()), expected);
}

TEST(RpcForms, MalformedGeomFilesAreRefusedWithFileAndLine) {
  const std::string g = pinned_geom();
  auto p = scratch("bad.geom");
  expect_error(p, std::regex_replace(g, std::regex("lat_off:  43"), "lat_off:  north"), "bad.geom:7: lat_off: 'north' is not a number");
  expect_error(p, std::regex_replace(g, std::regex("samp_off:  20\n"), ""), "bad.geom: missing samp_off");
  expect_error(p, std::regex_replace(g, std::regex("line_den_coeff_07:[^\n]*\n"), ""), "missing line_den_coeff_07");
  expect_error(p, g + "line_off: 11\n", "line_off given twice (first at line");
  expect_error(p, "bias_error: 0\nno colon here\n", "bad.geom:2: expected 'key: value'");
  expect_error(p, std::regex_replace(g, std::regex("type:  ossimPleiadesModel"), "type:  ossimSpot5Model"),
               "type: ossimSpot5Model is not an OSSIM RPC model");
  expect_error(p, std::regex_replace(g, std::regex("type:  ossimPleiadesModel\n"), ""), "missing type");
  expect_error(p, std::regex_replace(g, std::regex("polynomial_format:  B"), "polynomial_format:  C"),
               "polynomial_format: 'C' (expected B");
  expect_error(p, std::regex_replace(g, std::regex("processing_level:  SENSOR"), "processing_level:  ORTHO"),
               "a ORTHO product: its ossimPleiadesModel carries no RPC");
  expect_error(p, g + "support_data.note:  \"\"\"never closed\n", "support_data.note: a \"\"\" value without its closing");
  // a model that cannot be right is refused as in every form
  expect_error(p, std::regex_replace(g, std::regex("samp_scale:  1000"), "samp_scale:  0"), "SAMP_SCALE is 0");
}

// GDAL's RPC metadata is RPC00B's (alg/gdal_rpc.cpp: "the center of upper left pixel = 0,0"): taken as it is.
TEST(RpcForms, AuxPixelsAreRpc00bs) {
  const RpcModel txt = pinned_from_txt();
  auto p = scratch("pinned.tif.aux.xml");
  write(p, pinned_aux());
  auto a = read_rpc_aux(p.string());
  ASSERT_TRUE(a.has_value());
  EXPECT_EQ(*a, txt);
  const Eigen::Vector2d q = a->project(5, 43, 0);
  EXPECT_EQ(q[0], 20);
  EXPECT_EQ(q[1], 10);
  // coefficients separated by commas too, as GDALExtractRPCInfo splits them
  const std::string commas = std::regex_replace(pinned_aux(), std::regex("0 0 "), "0, 0,");
  write(p, commas);
  EXPECT_EQ(read_rpc_file(p.string()), txt);
  // a PAM file without the RPC domain has no model: nothing, and an error when read as a model file
  write(p, "<PAMDataset>\n  <Metadata>\n    <MDI key=\"LINE_OFF\">10</MDI>\n  </Metadata>\n</PAMDataset>\n");
  EXPECT_FALSE(read_rpc_aux(p.string()).has_value());
  EXPECT_NE(error_of(p).find("pinned.tif.aux.xml: no RPC metadata domain"), std::string::npos) << error_of(p);
}

TEST(RpcForms, MalformedAuxFilesAreRefusedWithFileAndLine) {
  const std::string x = pinned_aux();
  auto p = scratch("bad.tif.aux.xml");
  expect_error(p, std::regex_replace(x, std::regex("<MDI key=\"LAT_OFF\">43"), "<MDI key=\"LAT_OFF\">x43"),
               "bad.tif.aux.xml:10: LAT_OFF: 'x43' is not a number");
  expect_error(p, std::regex_replace(x, std::regex("(LINE_NUM_COEFF\">)0 "), "$1"),
               "bad.tif.aux.xml:13: LINE_NUM_COEFF: 19 coefficients instead of 20");
  expect_error(p, std::regex_replace(x, std::regex("(LINE_NUM_COEFF\">0) "), "$1 zero "),
               "bad.tif.aux.xml:13: LINE_NUM_COEFF: 'zero' is not a number");
  expect_error(p, std::regex_replace(x, std::regex("    <MDI key=\"SAMP_SCALE\">1000</MDI>\n"), ""),
               "missing SAMP_SCALE in the RPC metadata domain");
  expect_error(p, pinned_aux("    <MDI key=\"LINE_OFF\">11</MDI>\n"), "bad.tif.aux.xml:24: LINE_OFF given twice (first at line 14)");
  expect_error(p, pinned_aux("    <MDI>1</MDI>\n"), ":24: an MDI element of the RPC domain without a key");
  expect_error(p, std::regex_replace(x, std::regex("domain=\"RPC\""), "domain=\"RPC"), "bad.tif.aux.xml:6: malformed attributes in <Metadata>");
  expect_error(p, std::regex_replace(x, std::regex("</PAMRasterBand>"), "</PAMRaster>"), "does not close <PAMRasterBand>");
}

// DIMAP v1 (PHRDIMAP.XML) numbers pixels from 1, as v2: its Col.B and Row.B are tpkit's offsets plus 1.
TEST(RpcForms, DimapV1PixelsAreOneBased) {
  const RpcModel txt = pinned_from_txt();
  RpcModel withdirect = txt;
  withdirect.has_direct = true;  // lon = lon_off + lon_scale * s, lat = lat_off - lat_scale * l (h = 0)
  withdirect.lon_num[1] = 1;
  withdirect.lat_num[2] = -1;
  withdirect.lon_den[0] = withdirect.lat_den[0] = 1;
  const std::string v1 = dimap_v1(withdirect);
  EXPECT_NE(v1.find("<Col>\n            <A>1000</A>\n            <B>21</B>"), std::string::npos);
  EXPECT_NE(v1.find("<Row>\n            <A>1000</A>\n            <B>11</B>"), std::string::npos);
  auto p = scratch("PHRDIMAP.XML");
  write(p, v1);
  EXPECT_EQ(rpc_form_of(p.string()), RpcForm::dimap);
  const RpcModel d = read_rpc_dimap(p.string());
  EXPECT_EQ(d, withdirect);
  RpcModel inverse = d;
  inverse.has_direct = false;
  inverse.lon_num = inverse.lon_den = inverse.lat_num = inverse.lat_den = RpcPoly{};
  EXPECT_EQ(inverse, txt);
  EXPECT_EQ(d.project(5, 43, 0), Eigen::Vector2d(20, 10));
  // the direct model reads image (sample, line) as v2's does: tpkit pixel (20, 10) is DIMAP (21, 11)
  EXPECT_NEAR((d.direct(20, 10, 0) - Eigen::Vector2d(5, 43)).norm(), 0, 1e-15);
  // arbitrary numbers come back exactly
  const RpcModel m = arbitrary_model();
  write(p, dimap_v1(m));
  RpcModel r = read_rpc_dimap(p.string());
  RpcModel m0 = m;
  m0.err_bias = m0.err_rand = 0;  // DIMAP carries no ERR_BIAS / ERR_RAND
  EXPECT_EQ(r, m0);
}

// GDAL's other place for a DIMAP RPC: Rational_Function_Model holding Inverse_Model, RFM_Validity ...
// without a Global_RFM element between them.
TEST(RpcForms, DimapWithoutGlobalRfmIsReadAsGdalReadsIt) {
  const RpcModel m = pinned_from_txt();
  const std::string v2 = format_rpc_dimap(m);
  auto p = scratch("RPC_no_global.XML");
  write(p, std::regex_replace(v2, std::regex(" *</?Global_RFM>\n"), ""));
  const RpcModel r = read_rpc_dimap(p.string());
  write(p, v2);
  EXPECT_EQ(r, read_rpc_dimap(p.string()));
  EXPECT_EQ(r.project(5, 43, 0), Eigen::Vector2d(20, 10));
}

TEST(RpcForms, MalformedDimapV1FilesAreRefusedWithFileAndLine) {
  const std::string v1 = dimap_v1(arbitrary_model());
  auto p = scratch("PHRDIMAP_bad.XML");
  const long col_line = 16;  // <F_COL>
  expect_error(p, std::regex_replace(v1, std::regex("<F_COL>[^ ]* "), "<F_COL>"),
               "PHRDIMAP_bad.XML:" + std::to_string(col_line) + ": Geoposition.Rational_Sensor_Model.Global_RFM.Inverse_Model.F_COL: 39 coefficients instead of 40");
  expect_error(p, std::regex_replace(v1, std::regex("<F_ROW>[^ ]* "), "<F_ROW>one "), "F_ROW: 'one' is not a number");
  expect_error(p, std::regex_replace(v1, std::regex("<F_LAT>[^<]*</F_LAT>"), ""), "incomplete Direct_Model (F_LON and F_LAT go together)");
  expect_error(p, std::regex_replace(v1, std::regex("<Row>\n            <A>4096.5</A>"), "<Row>\n            <C>4096.5</C>"),
               "missing Geoposition.Rational_Sensor_Model.Global_RFM.RFM_Validity.Row.A");
  expect_error(p, std::regex_replace(v1, std::regex("<B>2048.5</B>"), "<B>2048.5 px</B>"), "RFM_Validity.Col.B: '2048.5 px' is not a number");
  // the inverse model without its line: not taken for v2
  expect_error(p, std::regex_replace(v1, std::regex("<F_ROW>[^<]*</F_ROW>"), ""), "missing Geoposition.Rational_Sensor_Model.Global_RFM.Inverse_Model.F_ROW");
}

TEST(RpcForms, TruncatedFilesAreRefusedCleanly) {
  const RpcModel m = arbitrary_model();
  const std::pair<const char*, std::string> forms[] = {
      {"cut.geom", format_rpc_geom(m)}, {"cut.tif.aux.xml", format_rpc_aux(m)}, {"PHRDIMAP_cut.XML", dimap_v1(m)}};
  for (const auto& [name, text] : forms) {
    auto p = scratch(name);
    long refused = 0, cuts = 0;
    for (size_t cut = 0; cut < text.size(); cut += 13, ++cuts) {
      write(p, text.substr(0, cut));
      const std::string e = error_of(p);
      if (e.empty()) continue;
      ++refused;
      EXPECT_NE(e.find(name), std::string::npos) << e;
    }
    EXPECT_GE(refused, cuts - 1) << name;  // all but (at most) a cut inside the very last value
  }
}

TEST(RpcForms, SidecarsAreFoundBesideTheImage) {
  EXPECT_EQ(rpc_form_of("/d/img.tif.aux.xml"), RpcForm::aux);
  EXPECT_EQ(rpc_form_of("/d/IMG.TIF.AUX.XML"), RpcForm::aux);
  EXPECT_EQ(rpc_form_of("/d/img.geom"), RpcForm::geom);
  EXPECT_EQ(rpc_form_of("/d/RPC_a.XML"), RpcForm::dimap);
  EXPECT_STREQ(rpc_form_name(RpcForm::geom), "geom");
  EXPECT_STREQ(rpc_form_name(RpcForm::aux), "aux");
  const auto c = rpc_sidecar_candidates("/d/scene.tif");
  ASSERT_FALSE(c.empty());
  EXPECT_EQ(c.front(), "/d/scene.tif.aux.xml");
  EXPECT_NE(std::find(c.begin(), c.end(), "/d/scene.geom"), c.end());
  const auto v1 = rpc_sidecar_candidates("/d/IMG_R1C1.JP2");
  EXPECT_EQ(v1.back(), "/d/PHRDIMAP.XML");

  const RpcModel txt = pinned_from_txt();
  auto dir = scratch("side");
  fs::create_directories(dir);
  const std::string img = (dir / "scene.png").string();
  write(img, "not read");
  // an .aux.xml holding statistics only is passed over; the .geom is found
  write(dir / "scene.png.aux.xml", "<PAMDataset>\n  <PAMRasterBand band=\"1\">\n    <Metadata>\n"
                                   "      <MDI key=\"STATISTICS_MEAN\">588.3</MDI>\n    </Metadata>\n  </PAMRasterBand>\n</PAMDataset>\n");
  EXPECT_FALSE(find_image_rpc(img).has_value());
  write(dir / "scene.geom", pinned_geom());
  auto s = load_image_rpc(img);
  EXPECT_EQ(s.form, RpcForm::geom);
  EXPECT_EQ(s.model, txt);
  // the RPC domain of the .aux.xml comes before every sidecar named after the stem
  RpcModel shifted = txt;
  shifted.samp_off = 7;
  write_rpc_aux((dir / "scene.png.aux.xml").string(), shifted);
  s = load_image_rpc(img);
  EXPECT_EQ(s.form, RpcForm::aux);
  EXPECT_EQ(s.model.samp_off, 7);
  // a model file named as one of the forms is read as that form
  EXPECT_EQ(load_rpc_model((dir / "scene.geom").string()).form, RpcForm::geom);
  EXPECT_EQ(load_rpc_model((dir / "scene.png.aux.xml").string()).form, RpcForm::aux);
  // DIMAP v1: PHRDIMAP.XML beside the product's IMG_R1C1.JP2
  const std::string jp2 = (dir / "IMG_R1C1.JP2").string();
  write(jp2, "not read");
  write(dir / "PHRDIMAP.XML", dimap_v1(arbitrary_model()));
  s = load_image_rpc(jp2);
  EXPECT_EQ(s.form, RpcForm::dimap);
  EXPECT_EQ(s.path, (dir / "PHRDIMAP.XML").string());
  EXPECT_TRUE(s.model.has_direct);
}

// Issue 50: valid XML read as XML reads it, and what cannot be read refused with what it is. Before: a
// value in a CDATA section was empty, a character reference (&#45;) stayed in the text or key, a second
// Global_RFM elsewhere in the document was passed over for the one first in path order, a hexadecimal
// SAMP_OFF was taken (strtold), and '>' inside a quoted attribute ended the tag.
TEST(RpcForms, XmlReadAsXml) {
  const RpcModel m = pinned_from_txt();
  // GDAL's .aux.xml: single-quoted attributes, references in keys and values, a CDATA value, a '>' in an
  // attribute value, a comment inside a value
  std::string x = pinned_aux();
  x = std::regex_replace(x, std::regex("<Metadata domain=\"RPC\">"), "<Metadata note='a > b' domain='RPC'>");
  x = std::regex_replace(x, std::regex("<MDI key=\"LAT_OFF\">43<"), "<MDI key='LAT&#95;OFF'>4&#x33;<");
  x = std::regex_replace(x, std::regex("<MDI key=\"LINE_OFF\">10<"), "<MDI key=\"LINE_OFF\"><![CDATA[1]]><!-- ten -->0<");
  x = std::regex_replace(x, std::regex("<MDI key=\"SAMP_OFF\">20<"), "<MDI key=\"SAMP&#x5f;OFF\">&#50;0&#x2E;0<");
  auto p = scratch("refs.tif.aux.xml");
  write(p, x);
  EXPECT_EQ(read_rpc_file(p.string()), m);
  // DIMAP v2: every value of RFM_Validity in a CDATA section, one offset written with references
  const std::string v2 = format_rpc_dimap(m);
  auto d = scratch("RPC_cdata.XML");
  std::string cdata = std::regex_replace(v2, std::regex("<([A-Z_]+_(OFF|SCALE))>([^<]*)</"), "<$1><![CDATA[ $3 ]]></");
  cdata = std::regex_replace(cdata, std::regex("<LINE_OFF><!\\[CDATA\\[ 11 \\]\\]>"), "<LINE_OFF>&#49;1");
  ASSERT_NE(cdata, v2);
  write(d, cdata);
  write(scratch("RPC_plain.XML"), v2);
  EXPECT_EQ(read_rpc_dimap(d.string()), read_rpc_dimap(scratch("RPC_plain.XML").string()));
  // what is not XML's is refused with the line
  expect_error(p, std::regex_replace(x, std::regex("4&#x33;"), "4&three;"),
               "refs.tif.aux.xml:10: '&three;': not one of XML's five entities (&lt; &gt; &amp; &quot; &apos;) or a character reference");
  expect_error(p, std::regex_replace(x, std::regex("4&#x33;"), "4 & 3"), "refs.tif.aux.xml:10: '& 3': not one of XML's five entities");
  expect_error(p, std::regex_replace(x, std::regex("4&#x33;"), "4&#0;"), "refs.tif.aux.xml:10: '&#0;': not one of");
  expect_error(p, std::regex_replace(x, std::regex("LAT&#95;OFF"), "LAT&#x;OFF"), "refs.tif.aux.xml:10: '&#x;OFF': not one of");
  expect_error(p, std::regex_replace(x, std::regex("\\]\\]>"), "]>"), "refs.tif.aux.xml:14: unterminated CDATA section");
  // DIMAP: a second Global_RFM, at the same path or elsewhere, is a second model
  const std::string rfm = v2.substr(v2.find("    <Global_RFM>"), v2.find("</Global_RFM>") + 14 - v2.find("    <Global_RFM>"));
  const long second = 1 + std::count(v2.begin(), v2.begin() + static_cast<long>(v2.find("</Rational_Function_Model>")), '\n');
  expect_error(d, std::regex_replace(v2, std::regex("  </Rational_Function_Model>\n"), rfm + "  </Rational_Function_Model>\n"),
               "RPC_cdata.XML:" + std::to_string(second) + ": a second Global_RFM element (the first at line 9): two models");
  const std::string elsewhere = std::regex_replace(v2, std::regex("</Dimap_Document>"), "  <Other>\n" + rfm + "  </Other>\n</Dimap_Document>");
  expect_error(d, elsewhere, "a second Global_RFM element (the first at line 9)");
  // a hexadecimal pixel offset is not DIMAP's number
  expect_error(d, std::regex_replace(v2, std::regex("<SAMP_OFF>21<"), "<SAMP_OFF>0x15<"),
               "RPC_cdata.XML:" + std::to_string(1 + std::count(v2.begin(), v2.begin() + static_cast<long>(v2.find("<SAMP_OFF>")), '\n')) +
                   ": Rational_Function_Model.Global_RFM.RFM_Validity.SAMP_OFF: '0x15' is not a number");
}
