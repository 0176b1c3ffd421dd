// COLMAP 3.8: the database.db that feature_extractor and the matchers fill and mapper reads, and the
// text import form of feature_importer + matches_importer. This module is the one place that knows
// COLMAP's schema and conventions:
//  - pixels: COLMAP's (0, 0) is the top-left corner of the image, the centre of the top-left pixel is
//    (0.5, 0.5): COLMAP x = tpkit x + 0.5, y = tpkit y + 0.5 on writing, minus 0.5 on reading (here and
//    nowhere else);
//  - image_id and camera_id count from 1 in image order (peer_keypoints.hpp); one SIMPLE_PINHOLE camera
//    (model 0) per image, params float64 f, cx, cy = 1.2 max(w, h), w / 2, h / 2 (COLMAP's own guess
//    without EXIF), prior_focal_length 0: every image needs its size;
//  - keypoints: rows = keypoints, cols = 2, float32 x y, row-major; no descriptors;
//  - matches and two_view_geometries: pair_id = 2147483647 min(id1, id2) + max(id1, id2); data uint32,
//    rows x 2, the keypoint index of the smaller image id first; two_view_geometries config 3
//    (UNCALIBRATED) with F float64 3x3 row-major, x2^T F x1 = 0 in COLMAP pixels (image 1 = the smaller
//    id), estimated from the matches by the normalized 8-point method; a pair with fewer than 8 matches
//    gets its matches row only; E, H, qvec, tvec NULL;
//  - table tpkit_keypoint_ids (COLMAP ignores it): per image the tpkit id of each keypoint, int64,
//    rows x 1, so that reading back restores tpkit's ids; without it (a database COLMAP made) the id
//    of a keypoint is its index (point2D_idx);
//  - text form: FOLDER/keypoints/NAME.txt, "N 128" then per keypoint "x y 1 0" and 128 zeros
//    (feature_importer wants 128-d SIFT descriptors; no matcher runs on them), FOLDER/matches.txt:
//    "NAME1 NAME2", then one "idx1 idx2" line per match, a blank line after each pair
//    (matches_importer --match_type raw or inliers). NAME = the image's file name without folder.
#pragma once
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"
#include "tpkit/interop/peer_keypoints.hpp"

namespace tpkit {

constexpr long long kColmapMaxImageId = 2147483647;
// COLMAP's pixel centre offset (see above).
constexpr double kColmapPixelOffset = 0.5;

long long colmap_pair_id(long long image_id1, long long image_id2);

// Writes a new database (atomically; an existing file is replaced at commit). InputError when an
// image has no size.
void write_colmap_database(const std::string& path, const PeerKeypoints& k);
// Writes FOLDER/keypoints/NAME.txt and FOLDER/matches.txt (FOLDER must exist).
void write_colmap_text(const std::string& folder, const PeerKeypoints& k);

// One matches file per image pair that has matches: from two_view_geometries (the verified inlier
// matches, config >= 2) when `verified`, else from matches (raw). Images are named by COLMAP's image
// names, sized by their cameras.
std::vector<Matches> read_colmap_database(const std::string& path, bool verified);

// The fundamental matrix (x2^T F x1 = 0) of n >= 8 correspondences, rows x1 y1 x2 y2, by the normalized
// 8-point method with rank 2 enforced; Frobenius norm 1.
Eigen::Matrix3d fundamental_8point(const Eigen::MatrixX4d& xy);

}  // namespace tpkit
