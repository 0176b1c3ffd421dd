#include "tpkit/match/keypoint_cache.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"

namespace tpkit {

namespace {
constexpr const char* kMagic = "tpkit-sift 3";

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

namespace {
std::string cache_path_of(const std::string& dir, const ImageSource& src, const std::string& identity) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a(identity)));
  return (std::filesystem::path(dir) / (std::filesystem::path(src.path).filename().string() + "." + hex + ".sift")).string();
}

void create_cache_dir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir + ": cannot create the keypoint cache folder: " + ec.message());
}
}  // namespace

std::string keypoint_cache_path(const std::string& dir, const ImageSource& src, const SiftOptions& o) {
  return cache_path_of(dir, src, keypoint_cache_identity(src, o));
}

namespace {
// One record as stored: fields packed in this order, no padding (kRecordBytes), native byte order.
constexpr size_t kRecordBytes = 5 * 4 + 2 * 4 + 8 + 128;

void pack(const cv::KeyPoint& k, int64_t id, const uint8_t* desc, char* out) {
  const float f[5] = {k.pt.x, k.pt.y, k.size, k.angle, k.response};
  const int32_t i[2] = {k.octave, k.class_id};
  std::memcpy(out, f, sizeof f);
  std::memcpy(out + 20, i, sizeof i);
  std::memcpy(out + 28, &id, 8);
  std::memcpy(out + 36, desc, 128);
}

// Reads a line of at most `max` bytes; false if longer or at the end of the stream.
bool short_line(std::istream& in, std::string& line, size_t max) {
  line.clear();
  for (;;) {
    const int c = in.get();
    if (c == std::char_traits<char>::eof()) return false;
    if (c == '\n') return true;
    if (line.size() >= max) return false;
    line.push_back(static_cast<char>(c));
  }
}

// The records' checksum: FNV-1a over 8-byte words (native order) in four lanes (word k of each 32 bytes
// to lane k), the lanes folded in order at the end, bytes after the last whole 32 into lane 0 one by one.
// Each step is a bijection of the lane, so a change of any one word always changes the sum. Format 2's
// byte-wise FNV-1a was one chain of 164 dependent multiplies per record: 0.2 s of a 2500² region job's
// 4.3 s went to loading its 600 000 cached keypoints.
class RecordsHash {
 public:
  // `n` a multiple of 32 in every call but the last
  void add(const char* p, size_t n) {
    size_t k = 0;
    for (; k + 32 <= n; k += 32)
      for (int l = 0; l < 4; ++l) {
        uint64_t w;
        std::memcpy(&w, p + k + 8 * l, 8);
        h_[l] = (h_[l] ^ w) * kPrime;
      }
    for (; k < n; ++k) h_[0] = (h_[0] ^ static_cast<unsigned char>(p[k])) * kPrime;
  }
  uint64_t value() const {
    uint64_t h = kBasis;
    for (uint64_t l : h_) h = (h ^ l) * kPrime;
    return h;
  }

 private:
  static constexpr uint64_t kBasis = 1469598103934665603ull, kPrime = 1099511628211ull;
  uint64_t h_[4] = {kBasis, kBasis + 1, kBasis + 2, kBasis + 3};
};

// Records are read, hashed and written this many at a time (a multiple of 8: 8 records are 41 x 32 bytes).
constexpr size_t kChunkRecords = 8192;
}  // namespace

bool load_keypoints(const std::string& path, const std::string& identity, Keypoints& K) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::error_code ec;
  const auto file_size = std::filesystem::file_size(path, ec);
  if (ec) return false;
  std::string magic, ident;
  if (!short_line(in, magic, 64) || magic != kMagic || !short_line(in, ident, 1 << 16)) return false;
  const size_t sp = ident.rfind(" count=");
  if (sp == std::string::npos || ident.substr(0, sp) != identity) return false;
  long long n = -1;
  try {
    size_t used = 0;
    n = std::stoll(ident.substr(sp + 7), &used);
    if (used != ident.size() - sp - 7) return false;
  } catch (...) {
    return false;
  }
  // the count must be what the file holds: header, records, checksum (checked before any allocation)
  const unsigned long long header = magic.size() + ident.size() + 2;
  if (n < 0 || n > (1LL << 31) - 1 ||
      static_cast<unsigned long long>(file_size) != header + static_cast<unsigned long long>(n) * kRecordBytes + 8)
    return false;
  Keypoints out;
  out.kp.resize(static_cast<size_t>(n));
  out.id.resize(static_cast<size_t>(n));
  out.desc.create(static_cast<int>(n), 128, CV_8U);
  RecordsHash h;
  std::vector<char> buf(std::min<size_t>(static_cast<size_t>(n), kChunkRecords) * kRecordBytes);
  for (size_t i0 = 0; i0 < static_cast<size_t>(n); i0 += kChunkRecords) {
    const size_t m = std::min<size_t>(kChunkRecords, static_cast<size_t>(n) - i0);
    if (!in.read(buf.data(), static_cast<std::streamsize>(m * kRecordBytes))) return false;
    h.add(buf.data(), m * kRecordBytes);
    for (size_t j = 0; j < m; ++j) {
      const char* rec = buf.data() + j * kRecordBytes;
      const size_t i = i0 + j;
      float f[5];
      int32_t oc[2];
      int64_t id;
      std::memcpy(f, rec, sizeof f);
      std::memcpy(oc, rec + 20, sizeof oc);
      std::memcpy(&id, rec + 28, 8);
      for (float v : f)
        if (!std::isfinite(v)) return false;
      if (f[0] < -0.5f || f[1] < -0.5f || !(f[2] > 0) || id < 0) return false;
      std::memcpy(out.desc.ptr<uint8_t>(static_cast<int>(i)), rec + 36, 128);
      out.kp[i] = cv::KeyPoint(f[0], f[1], f[2], f[3], f[4], oc[0], oc[1]);
      out.id[i] = id;
    }
  }
  uint64_t stored = 0;
  if (!in.read(reinterpret_cast<char*>(&stored), 8) || stored != h.value()) return false;
  K = std::move(out);
  return true;
}

void save_keypoints(const std::string& path, const std::string& identity, const Keypoints& K) {
  AtomicOutput out(path, /*transactional=*/false);  // a cache entry, not an output of the run
  std::ostream& s = out.stream();
  s << kMagic << "\n" << identity << " count=" << K.kp.size() << "\n";
  RecordsHash h;
  const size_t n = K.kp.size();
  std::vector<char> buf(std::min(n, kChunkRecords) * kRecordBytes);
  for (size_t i0 = 0; i0 < n; i0 += kChunkRecords) {
    const size_t m = std::min(kChunkRecords, n - i0);
    for (size_t j = 0; j < m; ++j)
      pack(K.kp[i0 + j], K.id[i0 + j], K.desc.ptr<uint8_t>(static_cast<int>(i0 + j)), buf.data() + j * kRecordBytes);
    h.add(buf.data(), m * kRecordBytes);
    s.write(buf.data(), static_cast<std::streamsize>(m * kRecordBytes));
  }
  const uint64_t sum = h.value();
  s.write(reinterpret_cast<const char*>(&sum), 8);
  out.commit();
}

namespace {
// The identity and the cache file of each tile of `tiles` (keypoint_cache.hpp: the image's identity
// plus the stretch and the tile index).
void tile_entries(const ImageSource& src, const SiftOptions& o, const Stretch& st, const std::vector<Tile>& tiles,
                  const std::string& dir, std::vector<std::string>& identity, std::vector<std::string>& path) {
  const std::string base = keypoint_cache_identity(src, o) + " stretch=" + format_number(st.lo) + "," + format_number(st.hi);
  identity.resize(tiles.size());
  path.resize(tiles.size());
  for (size_t t = 0; t < tiles.size(); ++t) {
    identity[t] = base + " tile=" + std::to_string(tiles[t].index);
    path[t] = cache_path_of(dir, src, identity[t]);
  }
}

bool load_entry(const std::string& path, const std::string& identity, Keypoints& K) {
  if (load_keypoints(path, identity, K)) return true;
  std::error_code ec;
  if (std::filesystem::exists(path, ec))
    warn(path + ": keypoint cache entry unusable (truncated, corrupt or of other options): detecting again");
  return false;
}
}  // namespace

Keypoints detect_sift_cached(const ImageSource& src, const SiftOptions& o, int threads, const std::string& dir,
                             Progress* progress, bool* from_cache) {
  if (from_cache) *from_cache = false;
  if (dir.empty()) return detect_sift_tiles(src, o, threads, progress);
  create_cache_dir(dir);
  std::error_code ec;
  const std::string identity = keypoint_cache_identity(src, o);
  const std::string path = keypoint_cache_path(dir, src, o);
  Keypoints K;
  if (load_entry(path, identity, K)) {
    if (from_cache) *from_cache = true;
    return K;
  }
  K = detect_sift_tiles(src, o, threads, progress);
  save_keypoints(path, identity, K);
  return K;
}

namespace {
// Keeps the keypoints of K inside w = [x0, x1) x [y0, y1) (order and ids kept).
void keep_inside(Keypoints& K, const std::array<double, 4>& w) {
  size_t n = 0;
  for (size_t i = 0; i < K.kp.size(); ++i) {
    const cv::Point2f p = K.kp[i].pt;
    if (!(p.x >= w[0] && p.x < w[2] && p.y >= w[1] && p.y < w[3])) continue;
    if (n != i) {
      K.kp[n] = K.kp[i];
      K.id[n] = K.id[i];
      std::memcpy(K.desc.ptr<uint8_t>(static_cast<int>(n)), K.desc.ptr<uint8_t>(static_cast<int>(i)), 128);
    }
    ++n;
  }
  if (n == K.kp.size()) return;  // all inside: nothing to copy
  K.kp.resize(n);
  K.id.resize(n);
  K.desc = n > 0 ? K.desc.rowRange(0, static_cast<int>(n)).clone() : cv::Mat(0, 128, CV_8U);
}
}  // namespace

Keypoints detect_sift_tiles_cached(const ImageSource& src, const SiftOptions& o, const Stretch& st, const std::vector<Tile>& tiles,
                                   int threads, const std::string& dir, long* cached_tiles, const std::array<double, 4>* window) {
  if (cached_tiles) *cached_tiles = 0;
  std::vector<Keypoints> per_tile(tiles.size());
  if (dir.empty()) {
    per_tile = detect_tiles_ranked(src, o, st, tiles, threads);
  } else {
    create_cache_dir(dir);
    std::vector<std::string> identity, path;
    tile_entries(src, o, st, tiles, dir, identity, path);
    std::vector<Tile> missing;
    std::vector<size_t> missing_at;
    for (size_t t = 0; t < tiles.size(); ++t) {
      if (load_entry(path[t], identity[t], per_tile[t])) {
        if (cached_tiles) ++*cached_tiles;
        if (window) keep_inside(per_tile[t], *window);  // each tile as it comes: one copy of the window's keypoints
        continue;
      }
      missing.push_back(tiles[t]);
      missing_at.push_back(t);
    }
    std::vector<Keypoints> found = detect_tiles_ranked(src, o, st, missing, threads);
    for (size_t k = 0; k < missing.size(); ++k) {
      save_keypoints(path[missing_at[k]], identity[missing_at[k]], found[k]);  // the whole tile
      if (window) keep_inside(found[k], *window);
      per_tile[missing_at[k]] = std::move(found[k]);
    }
  }
  if (window && dir.empty())
    for (Keypoints& K : per_tile) keep_inside(K, *window);
  return gather_tiles(std::move(per_tile), tiles, st);
}

std::vector<TileCacheEntry> cache_detection_tiles(const ImageSource& src, const SiftOptions& o, const Stretch& st,
                                                  const std::vector<Tile>& tiles, int threads, const std::string& dir) {
  if (dir.empty()) throw UsageError("detection into the cache needs a cache folder (--cache)");
  create_cache_dir(dir);
  std::vector<std::string> identity, path;
  tile_entries(src, o, st, tiles, dir, identity, path);
  std::vector<TileCacheEntry> out(tiles.size());
  std::vector<Tile> missing;
  std::vector<size_t> missing_at;
  for (size_t t = 0; t < tiles.size(); ++t) {
    out[t].tile = tiles[t];
    out[t].path = path[t];
    Keypoints K;
    if (load_entry(path[t], identity[t], K)) {
      out[t].keypoints = static_cast<long>(K.kp.size());
      out[t].cached = true;
    } else {
      missing.push_back(tiles[t]);
      missing_at.push_back(t);
    }
  }
  // a row of tiles at a time (the rows of the grid share their band of the image): memory of one
  // row's band, not of all the tiles' keypoints
  for (size_t r0 = 0; r0 < missing.size();) {
    size_t r1 = r0;
    while (r1 < missing.size() && missing[r1].cy0 == missing[r0].cy0) ++r1;
    const std::vector<Tile> row(missing.begin() + static_cast<long>(r0), missing.begin() + static_cast<long>(r1));
    std::vector<Keypoints> found = detect_tiles_ranked(src, o, st, row, threads);
    for (size_t k = 0; k < row.size(); ++k) {
      const size_t t = missing_at[r0 + k];
      save_keypoints(path[t], identity[t], found[k]);
      out[t].keypoints = static_cast<long>(found[k].kp.size());
    }
    r0 = r1;
  }
  return out;
}

void save_detection_report(const std::string& path, const ImageSource& src, const SiftOptions& o, const std::string& dir,
                           const std::vector<TileCacheEntry>& entries) {
  AtomicOutput out(path);
  Meta meta;
  meta_set(meta, "detector", detector_tag(o, src));
  meta_set(meta, "cache", dir);
  long total = 0, cached = 0;
  for (const auto& e : entries) total += e.keypoints, cached += e.cached ? 1 : 0;
  meta_set(meta, "tiles", std::to_string(entries.size()) + " detection tiles, " + std::to_string(cached) +
                              " found in the cache, " + std::to_string(total) + " keypoints");
  meta_set(meta, "core", "x0 y0 x1 y1: the tile's core [x0, x1) x [y0, y1), pixels (its keypoints); cached: 1 = found valid in the cache, 0 = detected");
  write_header(out.stream(), "detection", 1, {{src.path, src.info.width, src.info.height}}, meta,
               {"tile", "x0", "y0", "x1", "y1", "keypoints", "cached"});
  for (const auto& e : entries)
    write_record(out.stream(), {static_cast<double>(e.tile.index), static_cast<double>(e.tile.cx0), static_cast<double>(e.tile.cy0),
                                static_cast<double>(e.tile.cx1), static_cast<double>(e.tile.cy1), static_cast<double>(e.keypoints),
                                e.cached ? 1.0 : 0.0});
  out.commit();
}

}  // namespace tpkit
