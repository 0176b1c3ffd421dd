// The RPC forms of issue 26 beside the vendors' ones: DIMAP v1 (Pléiades' PHRDIMAP.XML, read). Each:
// write -> read is exact, its pixel convention is pinned by a model written by hand in that form and
// compared with the same model in txt form, malformed and truncated files are refused with file:line, and
// the sidecars are found beside an image.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>

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
      {"PHRDIMAP_cut.XML", dimap_v1(m)}};
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
  const auto v1 = rpc_sidecar_candidates("/d/IMG_R1C1.JP2");
  EXPECT_EQ(v1.back(), "/d/PHRDIMAP.XML");

  auto dir = scratch("side");
  fs::create_directories(dir);
  // DIMAP v1: PHRDIMAP.XML beside the product's IMG_R1C1.JP2
  const std::string jp2 = (dir / "IMG_R1C1.JP2").string();
  write(jp2, "not read");
  write(dir / "PHRDIMAP.XML", dimap_v1(arbitrary_model()));
  const auto s = load_image_rpc(jp2);
  EXPECT_EQ(s.form, RpcForm::dimap);
  EXPECT_EQ(s.path, (dir / "PHRDIMAP.XML").string());
  EXPECT_TRUE(s.model.has_direct);
}
