// NASA Ames Stereo Pipeline (ASP) match files, as VisionWorkbench writes and reads them
// (vw::ip::write_binary_match_file / read_binary_match_file, write_text_match_file).
//
// Binary PREFIX-STEM1__STEM2.match: uint64 n1, uint64 n2 (equal: one record per match), then the n1
// records of image 1, then the n2 records of image 2, match i being record i of each. A record is
// written field by field, no padding, little-endian (VW writes native order; ASP runs on little-endian
// machines): float32 x, y; int32 ix, iy; float32 orientation, scale, interest; uint8 polarity;
// uint32 octave, scale_lvl; uint64 ndesc; ndesc x float32 descriptor: 45 bytes with ndesc = 0, as
// written here.
// Text PREFIX-STEM1__STEM2.txt (ASP's --matches-as-txt): one match a line, "x1 y1 unc1 x2 y2 unc2".
//
// Conventions: VW pixel (0, 0) is the centre of the top-left pixel, as tpkit's: no offset. x, y are
// float32 in the binary form. scale (the text form's unc) is what ASP's bundle_adjust takes as the
// point's sigma: the record's `sigma` column (pixels, tp-match's LSM precision) floored at `min_sigma`,
// or 1 when the file has no sigma column; reading back gives it as the column `sigma` (of image 2's
// record). ix, iy = x, y rounded; orientation, interest, polarity, octave, scale_lvl = 0. STEM is the
// image's file name without folder and extension. ASP keeps no keypoint ids: reading back, ids come
// from positions (peer_keypoints.hpp).
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"

namespace tpkit {

constexpr size_t kAspRecordBytes = 45;

// PREFIX-STEM1__STEM2.match (or .txt).
std::string asp_match_file_name(const std::string& prefix, const std::string& image1, const std::string& image2, bool text);

void write_asp_match(std::ostream& os, const Matches& m, double min_sigma);
void write_asp_match_text(std::ostream& os, const Matches& m, double min_sigma);

// Reads a .match (binary) or .txt (text) file; the images are named by the stems in the file name
// (PREFIX-STEM1__STEM2: STEM1 is what follows the last '-' before "__"; a stem of `images` that ends
// the part before "__" wins, so stems may hold '-'; a name with several "__" is split where `images`
// say, and refused when they do not). Ids are left at the record index (assign_position_ids gives the
// real ones). Non-finite positions or scales are refused.
Matches read_asp_match(const std::string& path, const std::vector<std::string>& images = {});

}  // namespace tpkit
