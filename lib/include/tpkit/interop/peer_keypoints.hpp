// The keypoint lists that peer formats store per image (COLMAP, OpenMVG), built from tpkit matches
// files, and the ids given to tie points read back from formats that store positions only (ASP, MicMac).
//
// tpkit stores, per pair, keypoint ids and matched positions: (x1, y1) is image 1's keypoint, (x2, y2)
// the position refined in image 2, which can differ from one pair to the next for one keypoint id. A
// peer keypoint list therefore holds one entry per distinct (tpkit id, x, y) of an image, in order of
// first appearance over the files; a record becomes the pair of entries of its two positions. Images
// are numbered in order of first appearance (or in the order of `order` when given), from 0 here; each
// format adds its own base (COLMAP's image ids start at 1). Positions stay in tpkit's pixel convention
// here: every format converts at its own reader and writer only.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"

namespace tpkit {

struct PeerImage {
  ImageRef ref;                 // path, width, height (0 when unknown)
  std::vector<long long> id;    // tpkit keypoint id of each entry
  std::vector<double> x, y;     // position of each entry (tpkit pixels)
  size_t size() const { return x.size(); }
};

struct PeerPair {
  size_t image1 = 0, image2 = 0;      // indices into PeerKeypoints::images
  std::vector<uint32_t> idx1, idx2;   // entry indices, one per record of the source file
  size_t file = 0;                    // index of the source matches file
};

struct PeerKeypoints {
  std::vector<PeerImage> images;
  std::vector<PeerPair> pairs;
};

// Throws InputError naming m.source unless the file names two images (image1, image2 header lines:
// every peer format names its files or records after them) and they are two, not one image twice.
void check_peer_pair(const Matches& m);

// Builds the lists. `order` (image files, may be empty; each matched to the header image of the same
// path, file name or stem) fixes the image numbering; images not in it follow in order of first
// appearance. Throws InputError for a file that check_peer_pair refuses and for a second file of a pair
// (either way round: COLMAP and OpenMVG hold one set of matches per pair, and two would be written as
// two), UsageError when an image of `order` is in no file.
PeerKeypoints collect_peer_keypoints(const std::vector<Matches>& files, const std::vector<std::string>& order = {});

// The file name of an image without its folder ("a/b/img_01.tif" -> "img_01.tif") and without its
// extension too ("img_01").
std::string image_file_name(const std::string& path);
std::string image_stem(const std::string& path);

// Reading back from a format without keypoint ids: one id per distinct position of an image over all
// `files` (numbered from 0 in order of first appearance), so that tp-chain joins the pairs again.
void assign_position_ids(std::vector<Matches>& files);

// A matches file as read from a peer format: the two images, "# source-format:" and "# source:" lines,
// no records yet. Throws InputError naming `source` when an image name cannot stand in a tpkit header
// (empty, a line break or another control character, a space at either end) or both name one image.
Matches peer_matches(const ImageRef& image1, const ImageRef& image2, const std::string& format, const std::string& source);

// Records gathered one at a time by a reader, then stored in a Matches (ids, xy; extra untouched).
struct RecordList {
  std::vector<long long> id1, id2;
  std::vector<double> xy;  // x1 y1 x2 y2 per record
  void add(long long i1, double x1, double y1, long long i2, double x2, double y2);
  size_t size() const { return id1.size(); }
  void store(Matches& m) const;
};

// --images on the way back: each image of `files` whose file name (or stem) is that of one of `images`
// takes that path, and its size from the image file when the format gave none.
void name_images(std::vector<Matches>& files, const std::vector<std::string>& images);
// --images on the way out: images whose header gives no size take it from the matching image file
// (by path, file name or stem).
void size_images(PeerKeypoints& k, const std::vector<std::string>& images);

}  // namespace tpkit
