// The RPC00B / RPC00A TRE of NITF images: the WorldView-3 crops' models as GDAL reads them (the values
// CNES shareloc's test suite pins for wv3_20.NTF, read through rasterio / GDAL), the TRE written back
// character for character, RPC00A's term order, renormalization (exact) and the precision a written TRE
// keeps, and models the TRE cannot hold or that the producer marks as not valid.
#include <gtest/gtest.h>

#include <tuple>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/nitf_image.hpp"
#include "tpkit/rpc/rpc_crop.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_nitf.hpp"

using namespace tpkit;

namespace {
const std::string kWv3 = std::string(TPKIT_SHARED_DIR) + "/data/nitf-wv3/wv3_20.NTF";
const std::string kMarseille = std::string(TPKIT_SHARED_DIR) + "/data/pleiades-marseille/img_01.tif";
constexpr int kRpc00aTerm[20] = {0, 1, 2, 3, 4, 5, 6, 10, 7, 8, 9, 11, 14, 17, 12, 15, 18, 13, 16, 19};
}  // namespace

TEST(RpcNitf, Wv3ModelAsGdalReadsIt) {
  const RpcSource s = load_image_rpc(kWv3);
  EXPECT_EQ(s.form, RpcForm::nitf);
  const RpcModel& m = s.model;
  EXPECT_EQ(m.line_off, 17495);
  EXPECT_EQ(m.samp_off, 20749);
  EXPECT_EQ(m.line_scale, 17996);
  EXPECT_EQ(m.samp_scale, 21250);
  EXPECT_EQ(m.lat_off, -34.5043);
  EXPECT_EQ(m.lon_off, -58.6024);
  EXPECT_EQ(m.lat_scale, 0.0531);
  EXPECT_EQ(m.lon_scale, 0.0803);
  EXPECT_EQ(m.height_off, 31);
  EXPECT_EQ(m.height_scale, 501);
  EXPECT_EQ(m.err_bias, 0.87);
  EXPECT_EQ(m.err_rand, 0.33);
  EXPECT_EQ(m.line_num[0], 0.002401507);
  EXPECT_EQ(m.line_num[2], 1.002863);
  EXPECT_EQ(m.line_num[19], -4.526981e-08);
  EXPECT_EQ(m.line_den[1], 6.918796e-05);
  EXPECT_EQ(m.line_den[15], -0.001310256);
  EXPECT_EQ(m.samp_num[1], -1.021695);
  EXPECT_EQ(m.samp_num[19], -3.507909e-08);
  EXPECT_EQ(m.samp_den[1], 0.0007669113);
  EXPECT_EQ(m.samp_den[17], -1.725435e-08);
}

TEST(RpcNitf, Rpc00bWrittenBackCharacterForCharacter) {
  const NitfImage im = read_nitf_image(kWv3);
  const NitfTre& tre = *find_nitf_tre(im, "RPC00B");
  const RpcTre back = format_rpc00b_tre(parse_rpc_tre(tre, kWv3));
  EXPECT_EQ(back.tre.data, tre.data);
  EXPECT_EQ(back.max_change_px, 0.0);
}

TEST(RpcNitf, Rpc00aTermsRemapped) {
  const NitfTre b = *find_nitf_tre(read_nitf_image(kWv3), "RPC00B");
  NitfTre a{"RPC00A", b.data};
  for (size_t poly = 0; poly < 4; ++poly)
    for (int i = 0; i < 20; ++i) a.data.replace(81 + 240 * poly + 12 * kRpc00aTerm[i], 12, b.data.substr(81 + 240 * poly + 12 * i, 12));
  EXPECT_EQ(parse_rpc_tre(a, "a"), parse_rpc_tre(b, "b"));
}

TEST(RpcNitf, RenormalizedModelIsTheSameFunction) {
  const RpcModel m = *read_rpc_tiff(kMarseille);
  RpcModel to = m;
  to.line_off = 18000;
  to.samp_off = 19000.25;
  to.lat_off += 0.01;
  to.lon_off -= 0.02;
  to.height_off = 300;
  to.line_scale = 900;
  to.samp_scale = 700;
  to.lat_scale *= 1.3;
  to.lon_scale *= 0.8;
  to.height_scale = 800;
  const RpcModel r = renormalized_rpc(m, to);
  EXPECT_EQ(r.line_den[0], 1.0);
  EXPECT_EQ(r.samp_den[0], 1.0);
  double worst = 0;
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j)
      for (double h : {100.0, 565.0, 1000.0}) {
        const double lon = m.lon_off + 0.18 * m.lon_scale * i, lat = m.lat_off + 0.18 * m.lat_scale * j;
        worst = std::max(worst, (m.project(lon, lat, h) - r.project(lon, lat, h)).norm());
      }
  EXPECT_LT(worst, 1e-8);
}

TEST(RpcNitf, PleiadesModelKeptToTheTrePrecision) {
  // LINE_OFF 18339.5 and 11-digit degrees do not fit the TRE: written renormalized, within 0.01 px
  const RpcModel m = *read_rpc_tiff(kMarseille);
  const RpcTre t = format_rpc00b_tre(m);
  EXPECT_EQ(t.tre.data.size(), 1041u);
  EXPECT_EQ(t.model.line_off, 18340);
  EXPECT_GT(t.max_change_px, 0.0);
  EXPECT_LT(t.max_change_px, kMaxNitfRpcChangePx);
  EXPECT_EQ(format_rpc00b_tre(t.model).tre.data, t.tre.data);  // what was written writes the same again
}

TEST(RpcNitf, CropToNitfCarriesTheModel) {
  const std::string out = testing::TempDir() + "crop.ntf";
  const RpcModel m = *read_rpc_tiff(kMarseille);
  const double change = crop_image_with_rpc(kMarseille, 0, m, 100, 200, 300, 250, out);
  EXPECT_LT(change, kMaxNitfRpcChangePx);
  const RpcModel c = load_image_rpc(out).model;
  const Eigen::Vector2d p = m.project(5.4428, 43.2618, 150), q = c.project(5.4428, 43.2618, 150);
  EXPECT_NEAR(q.x(), p.x() - 100, change + 1e-9);
  EXPECT_NEAR(q.y(), p.y() - 200, change + 1e-9);
  const Raster a = read_region(kMarseille, 0, 100, 200, 300, 250), b = read_band(out);
  EXPECT_EQ(a.data, b.data);
}

TEST(RpcNitf, BadTresRefused) {
  const NitfTre good = *find_nitf_tre(read_nitf_image(kWv3), "RPC00B");
  auto message = [](const NitfTre& t) {
    try {
      parse_rpc_tre(t, "f.ntf");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  NitfTre unset = good;
  unset.data[0] = '0';
  EXPECT_NE(message(unset).find("SUCCESS is '0'"), std::string::npos);
  NitfTre shortt{"RPC00B", good.data.substr(0, 900)};
  EXPECT_NE(message(shortt).find("RPC00B TRE of 900 characters (1041 expected)"), std::string::npos);
  NitfTre nan = good;
  nan.data.replace(15, 6, "01x495");
  EXPECT_NE(message(nan).find("f.ntf: RPC00B TRE: LINE_OFF (characters 16 to 21) is '01x495', not a number"), std::string::npos);
  // issue 50: strtod read these as numbers; STDI-0002's fields are digits, with a sign, a decimal point or
  // an exponent only where the field's form has one
  const std::tuple<size_t, std::string, std::string> forged[] = {
      {15, "0x00fa", "LINE_OFF (characters 16 to 21) is '0x00fa', not a number of its form (digits)"},
      {15, "+17495", "LINE_OFF (characters 16 to 21) is '+17495'"},
      {15, "174 95", "LINE_OFF (characters 16 to 21) is '174 95'"},
      {1, "0x0.fp1", "ERR_BIAS (characters 2 to 8) is '0x0.fp1', not a number of its form (digits, a decimal point)"},
      {26, "-34.5e-0", "LAT_OFF (characters 27 to 34) is '-34.5e-0'"},
      {43, "+3E01", "HEIGHT_OFF (characters 44 to 48) is '+3E01', not a number of its form (digits, a sign)"},
      {48, "infini", "LINE_SCALE (characters 49 to 54) is 'infini'"},
      {81, "+0x1.33p-9  ", "LINE_NUM_COEFF_1 (characters 82 to 93) is '+0x1.33p-9  '"},
      {93, "-2.429637e-3", "LINE_NUM_COEFF_2 (characters 94 to 105) is '-2.429637e-3', not a number of its form (digits, a sign, a "
                           "decimal point, an exponent E+d)"}};
  for (const auto& [at, text, what] : forged) {
    NitfTre t = good;
    t.data.replace(at, text.size(), text);
    EXPECT_NE(message(t).find(what), std::string::npos) << text << ": " << message(t);
  }
  // blanks around a number are passed over
  NitfTre padded = good;
  padded.data.replace(43, 5, "  +31");
  EXPECT_EQ(parse_rpc_tre(padded, "p").height_off, 31);
  NitfTre zero = good;
  zero.data.replace(76, 5, "+0000");
  EXPECT_NE(message(zero).find("HEIGHT_SCALE"), std::string::npos);
  // offsets below 0 cannot be written
  RpcModel m = parse_rpc_tre(good, "g");
  m.line_off = -40;
  EXPECT_THROW(format_rpc00b_tre(m), InputError);
}

// Issue 50: a second RPC00B that differs was passed over for the first; the same bytes twice are one model.
TEST(RpcNitf, TwoTresThatDisagreeRefused) {
  NitfImage im = read_nitf_image(kWv3);
  const NitfTre first = *find_nitf_tre(im, "RPC00B");
  EXPECT_EQ(first.offset, 404u + 502u);  // the image subheader's CETAG
  NitfTre second = first;
  second.offset = 9999;
  im.tres.push_back(NitfTre{"TESTAA", "x", 8888});
  im.tres.push_back(second);
  EXPECT_EQ(*read_rpc_nitf(im), parse_rpc_tre(first, "f"));
  im.tres.back().data.replace(15, 6, "017496");
  try {
    read_rpc_nitf(im);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("two RPC00B TREs that disagree (at bytes 906 and 9999)"), std::string::npos) << e.what();
  }
}
