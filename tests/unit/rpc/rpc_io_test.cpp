// RPC00B models in every form: read, write, read again identical; DIMAP's 1-based pixels pinned; bad files
// refused with file:line; the real Pléiades crops' tag read and used (project / localize / epipolar curve).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_model.hpp"

using namespace tpkit;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("tpkit-rpc-io-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d / name;
}
const std::string kData = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille";

RpcModel pleiades(int i) {
  auto m = read_rpc_tiff(kData + "/img_0" + std::to_string(i) + ".tif");
  if (!m) throw std::runtime_error("no RPC tag in the Pléiades crop");
  return *m;
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

// The error message of reading `p` as `form`, "" if it reads.
std::string error_of(const fs::path& p) {
  try {
    read_rpc_file(p.string());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(RpcIo, PleiadesTagProjectsIntoTheCrop) {
  ASSERT_TRUE(fs::exists(kData + "/img_01.tif")) << "the real data is missing: " << kData;
  auto info = image_info(kData + "/img_01.tif");
  RpcModel a = pleiades(1);
  Eigen::Vector2d ll = a.localize(info.width / 2.0, info.height / 2.0, a.height_off);
  Eigen::Vector2d back = a.project(ll[0], ll[1], a.height_off);
  EXPECT_NEAR(back[0], info.width / 2.0, 1e-8);
  EXPECT_NEAR(back[1], info.height / 2.0, 1e-8);
  EXPECT_NEAR(ll[1], 43.26, 0.05);
  EXPECT_NEAR(ll[0], 5.44, 0.1);
  for (int i = 2; i <= 3; ++i) {
    Eigen::Vector2d q = pleiades(i).project(ll[0], ll[1], a.height_off);
    EXPECT_GT(q[0], 0);
    EXPECT_LT(q[0], info.width);
    EXPECT_GT(q[1], 0);
    EXPECT_LT(q[1], info.height);
  }
  // the epipolar curve of that pixel in image 2 passes through the projection at every height
  RpcModel b = pleiades(2);
  auto curve = epipolar_curve(a, b, 512, 512, a.height_off - 100, a.height_off + 100, 5);
  ASSERT_EQ(curve.size(), 5u);
  for (const auto& c : curve) {
    Eigen::Vector2d l2 = a.localize(512, 512, c[2]);
    EXPECT_NEAR((b.project(l2[0], l2[1], c[2]) - c.head<2>()).norm(), 0, 1e-9);
  }
  EXPECT_NEAR(epipolar_distance(a, b, {512, 512}, curve[2].head<2>(), a.height_off - 100, a.height_off + 100), 0, 1e-6);
  // the analytic Jacobian agrees with differences
  Eigen::Matrix<double, 2, 3> J;
  Eigen::Vector3d g(ll[0], ll[1], a.height_off);
  a.project(g, J);
  const double d = 1e-7;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[k] = k < 2 ? d : 1e-3;
    Eigen::Vector2d fd = (a.project(g + e) - a.project(g - e)) / (2 * e[k]);
    EXPECT_NEAR((fd - J.col(k)).norm() / J.col(k).norm(), 0, 1e-5);
  }
}

TEST(RpcIo, EveryFormRoundTripsExactly) {
  ASSERT_TRUE(fs::exists(kData + "/img_01.tif")) << "the real data is missing: " << kData;
  RpcModel m = pleiades(1);
  // txt, rpb: RPC00B as it is
  for (const char* name : {"a_rpc.txt", "a.RPB"}) {
    auto p = scratch(name).string();
    write_rpc_file(p, rpc_form_of(p), m);
    RpcModel r = read_rpc_file(p);
    EXPECT_EQ(r, m) << name;
    write_rpc_file(p, rpc_form_of(p), r);
    EXPECT_EQ(read_rpc_file(p), m) << name;
  }
  // dimap: a direct model is added (fitted), the inverse model and the normalization come back exactly
  auto x = scratch("RPC_a.XML").string();
  write_rpc_dimap(x, m);
  RpcModel d = read_rpc_dimap(x);
  ASSERT_TRUE(d.has_direct);
  RpcModel inverse_only = d;
  inverse_only.has_direct = false;
  RpcModel m0 = m;
  m0.err_bias = m0.err_rand = 0;  // DIMAP carries no ERR_BIAS / ERR_RAND
  EXPECT_EQ(inverse_only, m0);
  write_rpc_dimap(x, d);
  EXPECT_EQ(read_rpc_dimap(x), d);
  // the fitted direct model is a good first guess of localize
  Eigen::Vector2d ll = d.localize(300, 700, d.height_off), guess = d.direct(300, 700, d.height_off);
  EXPECT_LT((ll - guess).norm(), 1e-6);  // degrees (~0.1 m)
  // tiff: a copy of the image with the tag
  auto t = scratch("copy.tif").string();
  write_rpc_tiff_copy(kData + "/img_02.tif", t, m);
  auto tm = read_rpc_tiff(t);
  ASSERT_TRUE(tm.has_value());
  EXPECT_EQ(*tm, m);
  EXPECT_EQ(image_info(t).width, image_info(kData + "/img_02.tif").width);
}

TEST(RpcIo, ShortestDecimalsRoundTripArbitraryDoubles) {
  RpcModel m;
  m.err_bias = 0.1;
  m.err_rand = 1.0 / 3;
  m.line_off = 4095.5;
  m.samp_off = 0.1;  // not exact after "+ 1": the DIMAP writer picks a decimal that reads back
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
  }
  for (const char* name : {"b_RPC.TXT", "b.rpb"}) {
    auto p = scratch(name).string();
    write_rpc_file(p, rpc_form_of(p), m);
    EXPECT_EQ(read_rpc_file(p), m) << name;
  }
  m.has_direct = true;
  for (int i = 0; i < 20; ++i) {
    m.lon_num[i] = 1e-5 * i + 0.1;
    m.lat_num[i] = -1e-6 * i;
    m.lon_den[i] = m.lat_den[i] = i ? 1e-9 : 1;
  }
  m.err_bias = m.err_rand = 0;
  auto x = scratch("RPC_b.XML").string();
  write_rpc_dimap(x, m);
  EXPECT_EQ(read_rpc_dimap(x), m);
}

TEST(RpcIo, DimapPixelsAreOneBased) {
  RpcModel m;
  m.line_off = 10;
  m.samp_off = 20;
  m.lat_off = 43;
  m.lon_off = 5;
  m.height_off = 0;
  m.lat_scale = m.lon_scale = 0.01;
  m.line_scale = m.samp_scale = 1000;
  m.height_scale = 100;
  m.line_den[0] = m.samp_den[0] = 1;
  m.samp_num[1] = 1;  // x = samp_off + samp_scale * L
  m.line_num[2] = -1; // y = line_off - line_scale * P
  std::string xml = format_rpc_dimap(m);
  // tpkit (0, 0) = DIMAP (1, 1): the file says 21 and 11
  EXPECT_NE(xml.find("<SAMP_OFF>21</SAMP_OFF>"), std::string::npos);
  EXPECT_NE(xml.find("<LINE_OFF>11</LINE_OFF>"), std::string::npos);
  auto p = scratch("RPC_c.XML");
  write(p, xml);
  RpcModel r = read_rpc_dimap(p.string());
  EXPECT_EQ(r.samp_off, 20);
  EXPECT_EQ(r.line_off, 10);
  // the ground point at the offsets projects to tpkit pixel (20, 10), i.e. DIMAP (21, 11)
  Eigen::Vector2d q = r.project(5, 43, 0);
  EXPECT_DOUBLE_EQ(q[0], 20);
  EXPECT_DOUBLE_EQ(q[1], 10);
  // a hand-written DIMAP file whose pixel (1, 1) sees (lon_off, lat_off): tpkit pixel (0, 0)
  std::string hand = std::regex_replace(xml, std::regex("<SAMP_OFF>21</SAMP_OFF>"), "<SAMP_OFF>1</SAMP_OFF>");
  hand = std::regex_replace(hand, std::regex("<LINE_OFF>11</LINE_OFF>"), "<LINE_OFF>1</LINE_OFF>");
  write(p, hand);
  Eigen::Vector2d o = read_rpc_dimap(p.string()).project(5, 43, 0);
  EXPECT_DOUBLE_EQ(o[0], 0);
  EXPECT_DOUBLE_EQ(o[1], 0);
}

// DIMAP v3 (Pléiades Neo): ImagetoGround_Values / GroundtoImage_Values and, in RFM_Validity, an
// ImagetoGround_Validity_Domain whose FIRST_COL / FIRST_ROW number the top-left pixel's centre, 0 or 1
// (GDAL subtracts FIRST_COL from the offsets). Pinned on a v3 file made from the v2 text of a model.
TEST(RpcIo, DimapV3OffsetsCountFromFirstColAndFirstRow) {
  RpcModel m;
  m.line_off = 10, m.samp_off = 20, m.lat_off = 43, m.lon_off = 5, m.height_off = 0;
  m.lat_scale = m.lon_scale = 0.01;
  m.line_scale = m.samp_scale = 1000;
  m.height_scale = 100;
  m.line_den[0] = m.samp_den[0] = 1;
  m.samp_num[1] = 1;
  m.line_num[2] = -1;
  std::string v3 = format_rpc_dimap(m);
  v3 = std::regex_replace(v3, std::regex("Direct_Model_Validity_Domain"), "ImagetoGround_Validity_Domain");
  v3 = std::regex_replace(v3, std::regex("Inverse_Model_Validity_Domain"), "GroundtoImage_Validity_Domain");
  v3 = std::regex_replace(v3, std::regex("Direct_Model"), "ImagetoGround_Values");
  v3 = std::regex_replace(v3, std::regex("Inverse_Model"), "GroundtoImage_Values");
  auto with_origin = [&](const std::string& first, const std::string& samp, const std::string& line) {
    std::string t = std::regex_replace(v3, std::regex("<FIRST_ROW>[^<]*</FIRST_ROW>"), "<FIRST_ROW>" + first + "</FIRST_ROW>");
    t = std::regex_replace(t, std::regex("<FIRST_COL>[^<]*</FIRST_COL>"), "<FIRST_COL>" + first + "</FIRST_COL>");
    t = std::regex_replace(t, std::regex("<SAMP_OFF>[^<]*</SAMP_OFF>"), "<SAMP_OFF>" + samp + "</SAMP_OFF>");
    return std::regex_replace(t, std::regex("<LINE_OFF>[^<]*</LINE_OFF>"), "<LINE_OFF>" + line + "</LINE_OFF>");
  };
  auto p = scratch("RPC_v3.XML");
  // FIRST_COL = FIRST_ROW = 0: the offsets are tpkit's as written
  write(p, with_origin("0", "20", "10"));
  RpcModel r = read_rpc_dimap(p.string());
  EXPECT_EQ(r.samp_off, 20);
  EXPECT_EQ(r.line_off, 10);
  // FIRST_COL = FIRST_ROW = 1: one-based like v2
  write(p, with_origin("1", "21", "11"));
  r = read_rpc_dimap(p.string());
  EXPECT_EQ(r.samp_off, 20);
  EXPECT_EQ(r.line_off, 10);
  // any other first pixel is refused with its line
  write(p, with_origin("2", "21", "11"));
  try {
    read_rpc_dimap(p.string());
    FAIL() << "FIRST_COL 2 was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the first pixel is numbered 0 or 1"), std::string::npos) << e.what();
  }
}

TEST(RpcIo, MalformedFilesAreRefusedWithFileAndLine) {
  RpcModel m;
  m.line_den[0] = m.samp_den[0] = 1;
  m.samp_num[1] = m.line_num[2] = 1;
  std::string txt = format_rpc_txt(m);
  auto p = scratch("bad_rpc.txt");
  write(p, std::regex_replace(txt, std::regex("LAT_OFF: 0"), "LAT_OFF: zero"));
  EXPECT_NE(error_of(p).find("bad_rpc.txt:5: LAT_OFF: 'zero' is not a number"), std::string::npos) << error_of(p);
  write(p, std::regex_replace(txt, std::regex("SAMP_DEN_COEFF_20: 0\n"), ""));
  EXPECT_NE(error_of(p).find("missing SAMP_DEN_COEFF_20"), std::string::npos) << error_of(p);
  write(p, txt + "garbage\n");
  EXPECT_NE(error_of(p).find("bad_rpc.txt:93: expected 'KEY: value'"), std::string::npos) << error_of(p);
  write(p, "LINE_OFF: 1 pixels\n" + txt.substr(txt.find("SAMP_OFF")));
  EXPECT_EQ(error_of(p), "");  // unit words are allowed
  write(p, txt + "LINE_OFF: 3\n");
  EXPECT_NE(error_of(p).find(":93: LINE_OFF given twice"), std::string::npos) << error_of(p);

  std::string rpb = format_rpc_rpb(m);
  auto b = scratch("bad.RPB");
  write(b, std::regex_replace(rpb, std::regex("latOffset = 0;"), "latOffset = ;"));
  EXPECT_NE(error_of(b).find("bad.RPB:9: latOffset: ';' is not a number"), std::string::npos) << error_of(b);
  write(b, rpb.substr(0, rpb.find("END;")));
  EXPECT_NE(error_of(b).find("missing END;"), std::string::npos) << error_of(b);
  std::string short_coef = std::regex_replace(rpb, std::regex("lineNumCoef = \\(\n\t\t\t0,"), "lineNumCoef = (");
  write(b, short_coef);
  EXPECT_NE(error_of(b).find("bad.RPB:17: lineNumCoef: 19 coefficients instead of 20"), std::string::npos) << error_of(b);

  std::string xml = format_rpc_dimap(m);
  auto x = scratch("RPC_bad.XML");
  write(x, std::regex_replace(xml, std::regex("</Inverse_Model>"), "</Inverse>"));
  EXPECT_NE(error_of(x).find("RPC_bad.XML:"), std::string::npos);
  EXPECT_NE(error_of(x).find("does not close <Inverse_Model>"), std::string::npos) << error_of(x);
  write(x, std::regex_replace(xml, std::regex("<LAT_OFF>0</LAT_OFF>"), "<LAT_OFF>x</LAT_OFF>"));
  EXPECT_NE(error_of(x).find("is not a number"), std::string::npos) << error_of(x);
  EXPECT_NE(error_of(x).find("RPC_bad.XML:"), std::string::npos) << error_of(x);
  write(x, "<a><b>1</b></a>\n");
  EXPECT_NE(error_of(x).find("no Global_RFM"), std::string::npos) << error_of(x);

  auto t = scratch("notatiff.tif");
  write(t, "hello\n");
  EXPECT_NE(error_of(t).find("not a TIFF"), std::string::npos);
}

TEST(RpcIo, SidecarsAreFoundBesideTheImageAndOverridden) {
  RpcModel m;
  m.line_den[0] = m.samp_den[0] = 1;
  m.samp_num[1] = m.line_num[2] = 1;
  auto dir = scratch("side");
  fs::create_directories(dir);
  auto img = (dir / "scene.png").string();
  write(img, "not read");
  EXPECT_FALSE(find_image_rpc(img).has_value());
  try {
    load_image_rpc(img);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no RPC model"), std::string::npos);
  }
  write_rpc_rpb((dir / "scene.RPB").string(), m);
  auto s = load_image_rpc(img);
  EXPECT_EQ(s.form, RpcForm::rpb);
  RpcModel m2 = m;
  m2.line_off = 7;
  auto other = (dir / "other_rpc.txt").string();
  write_rpc_txt(other, m2);
  auto o = load_image_rpc(img, parse_rpc_overrides({img + "=" + other}));
  EXPECT_EQ(o.model.line_off, 7);
  EXPECT_EQ(o.form, RpcForm::txt);
  EXPECT_THROW(parse_rpc_overrides({"noequals"}), UsageError);
  auto c = rpc_sidecar_candidates("/d/IMG_PHR1A_P_001_R1C1.TIF");
  EXPECT_NE(std::find(c.begin(), c.end(), "/d/RPC_PHR1A_P_001.XML"), c.end());
}

TEST(RpcIo, TruncatedFilesAreRefusedCleanly) {
  RpcModel m;
  m.line_den[0] = m.samp_den[0] = 1;
  m.samp_num[1] = m.line_num[2] = 1;
  m.lat_scale = m.lon_scale = 0.01;
  m.line_scale = m.samp_scale = 500;
  const std::pair<const char*, std::string> forms[] = {
      {"cut_rpc.txt", format_rpc_txt(m)}, {"cut.RPB", format_rpc_rpb(m)}, {"RPC_cut.XML", format_rpc_dimap(m)}};
  for (const auto& [name, text] : forms) {
    auto p = scratch(name);
    long refused = 0;
    for (size_t cut = 0; cut < text.size(); cut += 13) {
      write(p, text.substr(0, cut));
      try {
        read_rpc_file(p.string());
      } catch (const InputError& e) {
        ++refused;
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      }
    }
    EXPECT_GT(refused, static_cast<long>(text.size() / 13) - 2) << name;  // all but (at most) a cut at the very end
  }
}

TEST(RpcIo, DimapTilesOtherThanTheFirstAreRefused) {
  // RPC_NAME.XML is the whole image's model, whose top-left pixel is tile R1C1's: tile R2C1 would get
  // pixels of the whole image, so it is refused rather than given a model off by the tile's offset
  const fs::path dir = fs::path(testing::TempDir()) / "dimap_tiles";
  fs::create_directories(dir);
  const RpcModel m = *read_rpc_tiff(std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/img_01.tif");
  write_rpc_dimap((dir / "RPC_PHR1A_X.XML").string(), m);
  for (const char* tile : {"IMG_PHR1A_X_R1C1.JP2", "IMG_PHR1A_X_R2C1.JP2"}) std::ofstream((dir / tile).string()) << "x";
  EXPECT_EQ(load_image_rpc((dir / "IMG_PHR1A_X_R1C1.JP2").string()).form, RpcForm::dimap);
  try {
    load_image_rpc((dir / "IMG_PHR1A_X_R2C1.JP2").string());
    ADD_FAILURE() << "tile R2C1 given the whole image's model";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tile R2C1 of a DIMAP product: RPC_PHR1A_X.XML is the model of the whole image"), std::string::npos) << e.what();
  }
}
