// OpenMVG tie points: the regions (.feat) and matches files of openMVG_main_ComputeFeatures /
// ComputeMatches, which the SfM engines read.
//
// FOLDER/STEM.feat: one keypoint a line, "x y scale orientation" (SIOPointFeature; a line of two or six
// numbers, the point and affine forms, is read too); the keypoint index is the line number from 0.
// FOLDER/matches.f.txt: per pair "I J" (view ids, I < J), then N, then N lines "i j" of keypoint
// indices of view I and view J. FOLDER/sfm_data.json: the views (id_view, filename, width, height) in
// cereal's JSON form, views only (no intrinsics, poses or structure), so that the view ids have names.
// Conventions: OpenMVG's pixel (0, 0) is the centre of the top-left pixel, as tpkit's: no offset; x, y
// are written as float32 (OpenMVG reads float), scale 1, orientation 0. View ids count from 0 in
// image order (peer_keypoints.hpp). OpenMVG keeps no tpkit ids: reading back, a keypoint's id is its
// index in the .feat file.
#pragma once
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"
#include "tpkit/interop/peer_keypoints.hpp"

namespace tpkit {

// Writes FOLDER/STEM.feat per image, FOLDER/matches.f.txt and FOLDER/sfm_data.json (FOLDER must exist).
void write_openmvg(const std::string& folder, const PeerKeypoints& k);

// Reads a matches file; the .feat files and sfm_data.json are looked for beside it. Without
// sfm_data.json, view v is images[v] (--images).
std::vector<Matches> read_openmvg(const std::string& matches_path, const std::vector<std::string>& images = {});

}  // namespace tpkit
