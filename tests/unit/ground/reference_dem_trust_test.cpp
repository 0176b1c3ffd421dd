// Reference DEMs as others write them (issue 50; each case names its item): fixtures are write_reference_dem's
// files with keys or tags changed in place, or written here with libtiff where tpkit's writer has no such layout.
#include <geotiff/geotiff.h>
#include <geotiff/geovalues.h>
#include <geotiff/xtiffio.h>
#include <gtest/gtest.h>
#include <tiffio.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "../limited_process.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/ground/dem_compare.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "utm_dem_fixture.hpp"

using namespace tpkit;

namespace {

std::string scratch(const std::string& name) { return tpkit_test::scratch("reference_dem_trust", name); }

// The InputError's message of `f`, "" when it throws none.
std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// Item 13: a datum is a keyword or a grid's name; PROJ's optional '@' (no grid when missing), a list, spaces
// and '+' parameters are refused naming the option rather than pasted into the PROJ definition.
TEST(ReferenceDemKeys, DatumOptionIsAGridNameOnly) {
  for (const std::string datum : {"@missing.gtx", "@egm96_15.gtx", "egm96_15.gtx +multiplier=1000", "egm96_15.gtx+multiplier=1000",
                                  "missing.gtx,egm96_15.gtx", "egm96_15.gtx\t"}) {
    const std::string e = refusal([&] { VerticalDatum d(datum); });
    EXPECT_EQ(e.rfind("--dem-datum '" + datum + "': neither ellipsoid, egm96, egm2008 nor a grid's file name", 0), 0u) << e;
  }
  // The grid behind egm96 named by its file, found in PROJ's search path: the same undulation.
  VerticalDatum by_file("egm96_15.gtx"), named("egm96");
  EXPECT_DOUBLE_EQ(by_file.undulation(5.4, 43.3), named.undulation(5.4, 43.3));
}

