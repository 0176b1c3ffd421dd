#include "tpkit/keypoint_cache.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tpkit/atomic_output.hpp"
#include "tpkit/error.hpp"
#include "tpkit/tool_support.hpp"

namespace tpkit {

namespace {
constexpr const char* kMagic = "tpkit-sift 1";

struct Record {
  float x, y, size, angle, response;
  int32_t octave, class_id;
  int64_t id;
};

uint64_t fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}
}  // namespace

std::string keypoint_cache_identity(const ImageSource& src, const SiftOptions& o) {
  std::error_code ec;
  const std::filesystem::path abs = std::filesystem::absolute(src.path, ec);
  struct stat sb {};
  if (::stat(src.path.c_str(), &sb) != 0) throw InputError(src.path + ": cannot stat the image for the keypoint cache");
  std::ostringstream s;
  s << "image=" << (ec ? src.path : abs.lexically_normal().string()) << " bytes=" << sb.st_size
    << " mtime=" << sb.st_mtim.tv_sec << "." << sb.st_mtim.tv_nsec << " detector=" << detector_tag(o, src);
  return s.str();
}

std::string keypoint_cache_path(const std::string& dir, const ImageSource& src, const SiftOptions& o) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a(keypoint_cache_identity(src, o))));
  return (std::filesystem::path(dir) / (std::filesystem::path(src.path).filename().string() + "." + hex + ".sift")).string();
}

bool load_keypoints(const std::string& path, const std::string& identity, Keypoints& K) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::string magic, ident;
  if (!std::getline(in, magic) || magic != kMagic || !std::getline(in, ident)) return false;
  const size_t sp = ident.rfind(" count=");
  if (sp == std::string::npos || ident.substr(0, sp) != identity) return false;
  long long n = -1;
  try {
    n = std::stoll(ident.substr(sp + 7));
  } catch (...) {
    return false;
  }
  if (n < 0 || n > (1LL << 31) - 1) return false;
  Keypoints out;
  out.kp.resize(static_cast<size_t>(n));
  out.id.resize(static_cast<size_t>(n));
  out.desc.create(static_cast<int>(n), 128, CV_8U);
  for (long long i = 0; i < n; ++i) {
    Record r;
    if (!in.read(reinterpret_cast<char*>(&r), sizeof r) || !in.read(reinterpret_cast<char*>(out.desc.ptr<uint8_t>(static_cast<int>(i))), 128))
      return false;
    out.kp[static_cast<size_t>(i)] = cv::KeyPoint(r.x, r.y, r.size, r.angle, r.response, r.octave, r.class_id);
    out.id[static_cast<size_t>(i)] = r.id;
  }
  if (in.peek() != std::char_traits<char>::eof()) return false;
  K = std::move(out);
  return true;
}

void save_keypoints(const std::string& path, const std::string& identity, const Keypoints& K) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  s << kMagic << "\n" << identity << " count=" << K.kp.size() << "\n";
  for (size_t i = 0; i < K.kp.size(); ++i) {
    const cv::KeyPoint& k = K.kp[i];
    const Record r{k.pt.x, k.pt.y, k.size, k.angle, k.response, k.octave, k.class_id, K.id[i]};
    s.write(reinterpret_cast<const char*>(&r), sizeof r);
    s.write(reinterpret_cast<const char*>(K.desc.ptr<uint8_t>(static_cast<int>(i))), 128);
  }
  out.commit();
}

Keypoints detect_sift_cached(const ImageSource& src, const SiftOptions& o, int threads, const std::string& dir,
                             Progress* progress, bool* from_cache) {
  if (from_cache) *from_cache = false;
  if (dir.empty()) return detect_sift_tiles(src, o, threads, progress);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir + ": cannot create the keypoint cache folder: " + ec.message());
  const std::string identity = keypoint_cache_identity(src, o);
  const std::string path = keypoint_cache_path(dir, src, o);
  Keypoints K;
  if (load_keypoints(path, identity, K)) {
    if (from_cache) *from_cache = true;
    return K;
  }
  K = detect_sift_tiles(src, o, threads, progress);
  save_keypoints(path, identity, K);
  return K;
}

}  // namespace tpkit
