// MicMac tie points (the Homol folder that Tapioca writes and Tapas / Campari read).
//
// HOMOL/Pastis<NAME1>/<NAME2>.txt or .dat holds the matches of image NAME1 with image NAME2 (NAME = the
// image's file name with its extension, no folder), NAME1's point first; MicMac reads both directions,
// so both files are written for each pair.
// Text: one match a line, "x1 y1 x2 y2 weight" (ElPackHomologue::StdPutInFile; a missing weight reads 1).
// Binary .dat (ElPackHomologue::StdPutInFile -> cPackNupletsHom::write; read back by
// cPackNupletsHom::read -> read_cont -> cNupletPtsHomologues::read): int32 dim (= 2), int32 N, then N
// records of int32 npoints (= 2), float64 weight, float64 x1, y1, x2, y2: 8 + 44 N bytes, no padding,
// little-endian (ELISE_fp writes native order; MicMac runs on little-endian machines).
// Conventions: MicMac's image coordinates are pixel units with integer values at pixel centres, as
// tpkit's: no offset. The weight is the record's `weight` column, else 1; reading back gives it as
// the column `weight`. MicMac keeps no keypoint ids: reading back, ids come from positions.
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include "tpkit/core/formats.hpp"

namespace tpkit {

constexpr size_t kMicmacHeaderBytes = 8;
constexpr size_t kMicmacRecordBytes = 44;

// HOMOL/Pastis<NAME1>/<NAME2>.txt|.dat
std::string micmac_homol_file_name(const std::string& homol, const std::string& image1, const std::string& image2, bool binary);

// Writes the matches of `m` in the direction image1 -> image2 (`reversed`: image2 -> image1).
void write_micmac_homol(std::ostream& os, const Matches& m, bool binary, bool reversed);

// One Pastis file (by extension: .dat binary, .txt text); image names from its folder and file name.
Matches read_micmac_homol(const std::string& path);
// A Homol folder: each pair once, read from Pastis<A>/<B> where A is the earlier in `order` (image
// names; else A < B) and the file of that direction exists, else from the other direction swapped.
// Where a pair has both a .dat and a .txt file, the binary one is read when `binary`, else the text.
std::vector<Matches> read_micmac_homol_folder(const std::string& homol, const std::vector<std::string>& order = {},
                                              bool binary = true);

}  // namespace tpkit
