// Keypoints and descriptors of an image kept on disk, so that an image matched in several pairs is
// detected once (tp-match --cache DIR), as COLMAP keeps its features in its database.
//
// One binary file per image and detector: DIR/<file name>.<16 hex digits>.sift, the digits a hash of
// the image's absolute path, size, modification time and the detector tag (detector_tag(): every
// option that changes the keypoints). Layout: a text line "tpkit-sift 3\n", a line with the identity
// string (path, size, mtime, tag) and the count, then per keypoint x y size angle response (float32),
// octave class_id (int32), id (int64), descriptor (128 bytes), packed (164 bytes) in the machine's byte
// order, then a 64-bit checksum of all record bytes (FNV-1a over 8-byte words in four lanes; format 2
// hashed byte by byte, and its files are detected again). A cache file is untrusted input: one whose
// identity line differs (edited image, other options, hash collision), whose count disagrees with its
// size, whose hash does not match, or that holds a non-finite value or a negative position, size or
// id counts as missing (with a warning) and is detected again and rewritten. Written atomically (temporary file + rename), so
// parallel runs that share a folder only ever read whole files.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "tpkit/match/sift_tiles.hpp"

namespace tpkit {

// The identity of (image, detector options) that a cache file must match.
std::string keypoint_cache_identity(const ImageSource& src, const SiftOptions& o);
std::string keypoint_cache_path(const std::string& dir, const ImageSource& src, const SiftOptions& o);

// True and K filled when `path` holds the keypoints of `identity`.
bool load_keypoints(const std::string& path, const std::string& identity, Keypoints& K);
void save_keypoints(const std::string& path, const std::string& identity, const Keypoints& K);

// detect_sift_tiles() through the cache folder `dir` (none when empty): loads when present, else
// detects and saves. `from_cache` (may be null) tells which.
Keypoints detect_sift_cached(const ImageSource& src, const SiftOptions& o, int threads, const std::string& dir,
                             Progress* progress = nullptr, bool* from_cache = nullptr);

// Region runs (tp-match --region): the keypoints of some tiles of the global detection grid
// (detect_sift_tile_set with the whole image's stretch `st`), each tile kept in its own cache file
// whose identity is the image's plus " tile=INDEX stretch=LO,HI", so that jobs on neighbouring regions
// that share the folder detect each tile once. `cached_tiles` (may be null) counts the tiles loaded.
// With `window` ([x0, x1) x [y0, y1), pixel-centre coordinates), only the keypoints inside it are kept,
// each tile filtered as it is loaded: memory of the window's keypoints, not of the whole tiles'.
Keypoints detect_sift_tiles_cached(const ImageSource& src, const SiftOptions& o, const Stretch& st, const std::vector<Tile>& tiles,
                                   int threads, const std::string& dir, long* cached_tiles = nullptr,
                                   const std::array<double, 4>* window = nullptr);

// Detection jobs of a scaled-out run (tp-match --detect, tp-plan's detect stage): each tile of `tiles`
// is detected with the image's stretch `st` into its cache file (the files detect_sift_tiles_cached
// reads), unless a valid one is there already; a row of tiles at a time, so that memory is one row's
// band of the image and one tile's detector, whatever the number of tiles. Throws UsageError without
// a folder.
struct TileCacheEntry {
  Tile tile;
  std::string path;    // its cache file
  long keypoints = 0;
  bool cached = false;  // found valid in the cache (else detected now)
};
std::vector<TileCacheEntry> cache_detection_tiles(const ImageSource& src, const SiftOptions& o, const Stretch& st,
                                                  const std::vector<Tile>& tiles, int threads, const std::string& dir);

// The record of such a job (file kind `detection`, tpkit-formats(5)): one line per tile with its core,
// its keypoint count and whether it was found in the cache.
void save_detection_report(const std::string& path, const ImageSource& src, const SiftOptions& o, const std::string& dir,
                           const std::vector<TileCacheEntry>& entries);

}  // namespace tpkit
