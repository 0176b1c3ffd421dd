#include "tpkit/interop/asp_match.hpp"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "binary_stream.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/interop/peer_keypoints.hpp"
#include "tpkit/core/text_table.hpp"

namespace tpkit {

namespace {

// The scale field of match r (see the header): sigma floored, or 1.
double asp_scale(const Matches& m, size_t r, double min_sigma) {
  const int c = m.extra.find("sigma");
  if (c < 0) return 1.0;
  return std::max(m.extra.values(r, c), min_sigma);
}

void put_record(std::ostream& os, double x, double y, double scale) {
  const float fx = static_cast<float>(x), fy = static_cast<float>(y);
  put_le<float>(os, fx);
  put_le<float>(os, fy);
  put_le<int32_t>(os, static_cast<int32_t>(std::lround(fx)));
  put_le<int32_t>(os, static_cast<int32_t>(std::lround(fy)));
  put_le<float>(os, 0.0f);   // orientation
  put_le<float>(os, static_cast<float>(scale));  // scale
  put_le<float>(os, 0.0f);   // interest
  put_le<uint8_t>(os, 0);    // polarity
  put_le<uint32_t>(os, 0);   // octave
  put_le<uint32_t>(os, 0);   // scale_lvl
  put_le<uint64_t>(os, 0);   // ndesc
}

struct AspPoint {
  double x, y, scale;  // float32 in the binary form
};

AspPoint get_record(ByteReader& in) {
  AspPoint p;
  p.x = in.get<float>("x");
  p.y = in.get<float>("y");
  in.get<int32_t>("ix");
  in.get<int32_t>("iy");
  in.get<float>("orientation");
  p.scale = in.get<float>("scale");
  in.get<float>("interest");
  in.get<uint8_t>("polarity");
  in.get<uint32_t>("octave");
  in.get<uint32_t>("scale_lvl");
  const uint64_t ndesc = in.get<uint64_t>("ndesc");
  if (ndesc > in.left() / 4)
    throw InputError(in.source(), 0, "truncated at byte " + std::to_string(in.offset()) + ": a record announces " +
                                         std::to_string(ndesc) + " descriptor values, more than the file holds");
  for (uint64_t k = 0; k < ndesc; ++k) in.get<float>("descriptor");
  if (!std::isfinite(p.x) || !std::isfinite(p.y))
    throw InputError(in.source(), 0, "a record at byte " + std::to_string(in.offset()) + " holds a non-finite position");
  if (!std::isfinite(p.scale))
    throw InputError(in.source(), 0, "a record at byte " + std::to_string(in.offset()) + " holds a non-finite scale (the point's sigma)");
  return p;
}

// The two stems of PREFIX-STEM1__STEM2.EXT. The name is split at a "__": the one there is, or, when
// there are several (a stem holding "__" itself), the one that `images` single out, a stem of theirs
// ending the part before it (after a '-') or making up the part after it; else the name is ambiguous.
std::pair<std::string, std::string> stems_of(const std::string& path, const std::vector<std::string>& images) {
  const std::string name = image_stem(path);
  std::vector<size_t> seps;
  for (size_t p = name.find("__"); p != std::string::npos; p = name.find("__", p + 1)) seps.push_back(p);
  if (seps.empty()) throw InputError(path, 0, "an ASP match file is named PREFIX-IMAGE1__IMAGE2.match: no '__' in the name");
  // the longest stem of `images` that ends `head` on a '-' (or is all of it), or ""
  auto image_ending = [&](const std::string& head) {
    std::string first;
    for (const auto& im : images) {
      const std::string s = image_stem(im);
      if (s.size() > first.size() && head.size() >= s.size() && head.compare(head.size() - s.size(), s.size(), s) == 0 &&
          (head.size() == s.size() || head[head.size() - s.size() - 1] == '-'))
        first = s;
    }
    return first;
  };
  auto is_image = [&](const std::string& stem) {
    for (const auto& im : images)
      if (image_stem(im) == stem) return true;
    return false;
  };
  std::vector<size_t> named;  // splits that `images` support
  for (size_t p : seps)
    if (!image_ending(name.substr(0, p)).empty() || is_image(name.substr(p + 2))) named.push_back(p);
  size_t sep = seps[0];
  if (named.size() == 1) sep = named[0];
  else if (seps.size() > 1)
    throw InputError(path, 0, "the name holds '__' " + std::to_string(seps.size()) +
                                  " times: cannot tell where IMAGE1 ends and IMAGE2 begins" +
                                  (images.empty() ? " (name the images with --images)" : " (--images fits none or several)"));
  const std::string head = name.substr(0, sep), second = name.substr(sep + 2);
  std::string first = image_ending(head);
  if (first.empty()) {
    const auto dash = head.rfind('-');
    first = dash == std::string::npos ? head : head.substr(dash + 1);
  }
  if (first.empty() || second.empty()) throw InputError(path, 0, "cannot tell the two image names from the file name");
  return {first, second};
}

struct AspRecords {
  RecordList records;
  std::vector<double> sigma;
  void add(const AspPoint& a, const AspPoint& b) {
    const long long r = static_cast<long long>(records.size());
    records.add(r, a.x, a.y, r, b.x, b.y);
    sigma.push_back(b.scale);
  }
};

void finish(Matches& m, const AspRecords& recs) {
  recs.records.store(m);
  const std::vector<double>& sigma = recs.sigma;
  m.extra.names = {"sigma"};
  m.extra.values = Eigen::Map<const Eigen::VectorXd>(sigma.data(), static_cast<Eigen::Index>(sigma.size()));
}

void read_binary(Matches& m, const std::string& path) {
  const std::string data = read_binary_file(path);
  ByteReader in(data, path);
  const uint64_t n1 = in.get<uint64_t>("the count of image 1"), n2 = in.get<uint64_t>("the count of image 2");
  if (n1 != n2)
    throw InputError(path, 0, "the counts disagree: " + std::to_string(n1) + " points of image 1, " + std::to_string(n2) +
                                  " of image 2");
  if (n1 > in.left() / (2 * kAspRecordBytes))
    throw InputError(path, 0, "truncated: " + std::to_string(n1) + " matches need at least " +
                                  std::to_string(16 + 2 * n1 * kAspRecordBytes) + " bytes, the file has " +
                                  std::to_string(data.size()));
  std::vector<AspPoint> p1;
  for (uint64_t i = 0; i < n1; ++i) p1.push_back(get_record(in));
  AspRecords recs;
  for (uint64_t i = 0; i < n2; ++i) recs.add(p1[i], get_record(in));
  if (in.left() != 0) throw InputError(path, 0, std::to_string(in.left()) + " bytes after the last record");
  finish(m, recs);
}

void read_text(Matches& m, const std::string& path) {
  std::ifstream in = open_input_file(path, InputKind::file);
  std::string line;
  AspRecords recs;
  for (long n = 1; read_text_line(in, line, path, n); ++n) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream s(line);
    AspPoint a, b;
    std::string extra;
    if (!(s >> a.x >> a.y >> a.scale >> b.x >> b.y >> b.scale) || (s >> extra))
      throw InputError(path, n, "an ASP text match is six numbers: x1 y1 unc1 x2 y2 unc2");
    if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y))
      throw InputError(path, n, "a position is not finite");
    if (!(a.scale > 0) || !(b.scale > 0) || !std::isfinite(a.scale) || !std::isfinite(b.scale))
      throw InputError(path, n, "the uncertainties must be finite and > 0");
    recs.add(a, b);
  }
  finish(m, recs);
}

}  // namespace

std::string asp_match_file_name(const std::string& prefix, const std::string& image1, const std::string& image2, bool text) {
  return prefix + "-" + image_stem(image1) + "__" + image_stem(image2) + (text ? ".txt" : ".match");
}

void write_asp_match(std::ostream& os, const Matches& m, double min_sigma) {
  const uint64_t n = m.size();
  put_le<uint64_t>(os, n);
  put_le<uint64_t>(os, n);
  for (size_t r = 0; r < m.size(); ++r) put_record(os, m.xy(r, 0), m.xy(r, 1), asp_scale(m, r, min_sigma));
  for (size_t r = 0; r < m.size(); ++r) put_record(os, m.xy(r, 2), m.xy(r, 3), asp_scale(m, r, min_sigma));
}

void write_asp_match_text(std::ostream& os, const Matches& m, double min_sigma) {
  for (size_t r = 0; r < m.size(); ++r) {
    const double s = asp_scale(m, r, min_sigma);
    os << format_number(m.xy(r, 0)) << ' ' << format_number(m.xy(r, 1)) << ' ' << format_number(s) << ' '
       << format_number(m.xy(r, 2)) << ' ' << format_number(m.xy(r, 3)) << ' ' << format_number(s) << '\n';
  }
}

Matches read_asp_match(const std::string& path, const std::vector<std::string>& images) {
  const auto [stem1, stem2] = stems_of(path, images);
  const bool text = std::filesystem::path(path).extension() == ".txt";
  Matches m = peer_matches(ImageRef{stem1, 0, 0}, ImageRef{stem2, 0, 0}, text ? "asp-txt" : "asp", path);
  if (text) read_text(m, path);
  else read_binary(m, path);
  return m;
}

}  // namespace tpkit
