// The --init file: physical values, geodetic positions through GeographicLib, and its errors.
#include "tpkit/cluster/cluster_init.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <sstream>

#include "tpkit/core/error.hpp"

using namespace tpkit;

namespace {
ClusterInit parse(const std::string& s) {
  std::istringstream in(s);
  return read_cluster_init(in, "init.txt");
}
std::string error_of(const std::string& s) {
  try {
    parse(s);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
const char* kPhysical =
    "px1 = 200\npy1 = -50 # comment\nrho1 = 800000\nalpha1 = 1.4\nbeta1 = 0.5\ngamma1 = 0.5\nres1 = 20\ntheta1 = 0.1\n"
    "cx1 = 1\ncy1 = 1\npx2 = 100\npy2 = 100\nrho2 = 800000\nalpha2 = 0.8\nbeta2 = 1\ngamma2 = 1.57\nres2 = 20\n";
}  // namespace

TEST(ClusterInit, ReadsPhysicalValues) {
  ClusterInit ci = parse(kPhysical);
  ASSERT_TRUE(ci.has_physical);
  EXPECT_FALSE(ci.has_H);
  EXPECT_EQ(ci.physical.view[0].px, 200);
  EXPECT_EQ(ci.physical.view[0].py, -50);
  EXPECT_EQ(ci.physical.view[0].theta, 0.1);
  EXPECT_EQ(ci.physical.view[1].gamma, 1.57);
  EXPECT_EQ(ci.physical.view[1].theta, 0);  // default
}

TEST(ClusterInit, ReadsTheShippedExample) {
  ClusterInit ci = read_cluster_init_file(std::string(TPKIT_SOURCE_DIR) + "/share/tpkit/cluster-init-example.txt");
  EXPECT_TRUE(ci.has_physical);
  EXPECT_EQ(ci.physical.view[1].py, 100);
}

TEST(ClusterInit, ErrorsNameTheLine) {
  EXPECT_NE(error_of(std::string(kPhysical) + "colour = 3\n").find("init.txt:18: unknown key 'colour'"), std::string::npos);
  EXPECT_NE(error_of(std::string(kPhysical) + "rho1 = 3\n").find("given twice"), std::string::npos);
  std::string bad = kPhysical;
  bad.replace(bad.find("beta1 = 0.5"), 11, "beta1 = 2.0");
  EXPECT_NE(error_of(bad).find("init.txt:5: beta1"), std::string::npos) << error_of(bad);
  bad = kPhysical;
  bad.replace(bad.find("res1 = 20"), 9, "res1 = -2");
  EXPECT_NE(error_of(bad).find("res1"), std::string::npos);
  EXPECT_NE(error_of("alpha1 = abc\n").find("not a number"), std::string::npos);
  EXPECT_NE(error_of("alpha1 = nan\n").find("not finite"), std::string::npos);
  EXPECT_NE(error_of("# nothing\n").find("no parameters"), std::string::npos);
  EXPECT_NE(error_of("h11 = 1\n").find("nine"), std::string::npos);
}

TEST(ClusterInit, HomographyStart) {
  ClusterInit ci = parse("h11 = 1\nh12 = 0\nh13 = 5\nh21 = 0\nh22 = 2\nh23 = 0\nh31 = 0\nh32 = 0\nh33 = 1\n");
  EXPECT_TRUE(ci.has_H);
  EXPECT_FALSE(ci.has_physical);
  EXPECT_EQ(ci.H(0, 2), 5);
  EXPECT_EQ(ci.H(1, 1), 2);
}

TEST(ClusterInit, LookAnglesFromGeodeticPositions) {
  // Straight up: elevation pi/2, distance = height difference.
  LookAngles up = look_angles(43.3, 5.4, 700000, 43.3, 5.4, 0);
  EXPECT_NEAR(up.beta, M_PI / 2, 1e-9);
  EXPECT_NEAR(up.rho, 700000, 1e-3);
  // A satellite due north at 694 km, 300 km away along the ground: azimuth pi/2 (x east, y north).
  GeographicLib::Geodesic g = GeographicLib::Geodesic::WGS84();
  double lat2, lon2;
  g.Direct(43.3, 5.4, 0.0, 300000, lat2, lon2);
  LookAngles n = look_angles(lat2, lon2, 694000, 43.3, 5.4, 0);
  EXPECT_NEAR(n.alpha, M_PI / 2, 1e-6);
  // Elevation from the local Cartesian coordinates computed independently.
  GeographicLib::LocalCartesian lc(43.3, 5.4, 0);
  double e, nn, u;
  lc.Forward(lat2, lon2, 694000, e, nn, u);
  EXPECT_NEAR(n.beta, std::atan2(u, std::hypot(e, nn)), 1e-12);
  EXPECT_GT(n.beta, 0.9);
  EXPECT_LT(n.beta, 1.3);
}

TEST(ClusterInit, GeodeticKeysGiveAnglesAndTargetPoints) {
  GeographicLib::Geodesic g = GeographicLib::Geodesic::WGS84();
  double slat, slon, s2lat, s2lon;
  g.Direct(43.3, 5.4, 90.0, 250000, slat, slon);    // satellite 1 east of the scene
  g.Direct(43.3, 5.4, 180.0, 400000, s2lat, s2lon);  // satellite 2 south
  std::ostringstream s;
  s.precision(17);
  s << "sat1_lat = " << slat << "\nsat1_lon = " << slon << "\nsat1_h = 694000\n"
    << "scene1_lat = 43.3\nscene1_lon = 5.4\nscene1_h = 0\nres1 = 0.7\n"
    << "sat2_lat = " << s2lat << "\nsat2_lon = " << s2lon << "\nsat2_h = 694000\n"
    << "scene2_lat = 43.301\nscene2_lon = 5.4\nscene2_h = 0\nres2 = 0.7\n";
  ClusterInit ci = parse(s.str());
  ASSERT_TRUE(ci.has_physical);
  EXPECT_NEAR(ci.physical.view[0].alpha, 0, 0.01);  // east
  EXPECT_NEAR(std::abs(ci.physical.view[1].alpha), M_PI / 2, 0.01);
  EXPECT_LT(ci.physical.view[1].alpha, 0);          // south
  EXPECT_NEAR(ci.physical.view[0].px, 0, 1e-6);     // origin = scene 1
  EXPECT_NEAR(ci.physical.view[1].py, 111.1, 0.5);  // 0.001 degree north
  EXPECT_GT(ci.physical.view[0].beta, ci.physical.view[1].beta);  // the farther satellite is lower
  // Below the horizon: impossible.
  std::string low = s.str();
  low.replace(low.find("sat1_h = 694000"), 15, "sat1_h = 1000");
  EXPECT_NE(error_of(low).find("below the horizon"), std::string::npos) << error_of(low);
  EXPECT_NE(error_of(s.str() + "alpha1 = 1\n").find("cannot be given with geodetic"), std::string::npos);
  std::string badlat = s.str();
  badlat.replace(badlat.find("scene2_lat = 43.301"), 19, "scene2_lat = 143.3");
  EXPECT_NE(error_of(badlat).find("outside [-90, 90]"), std::string::npos) << error_of(badlat);
}
