// NITF 2.1 / NSIF 1.0 images (MIL-STD-2500C; TREs after STDI-0002) without GDAL: the headers of the
// file and of its first image segment, its TREs (the RPC00B model of WorldView, GeoEye, ... products is
// one), and its pixels read by region: uncompressed (IC = NC, or NM with a block mask; band interleaves
// B, P, R and S; 8, 16 and 32-bit samples, ABPP bits right- or left-justified in them; many blocks, pad
// pixels at the right and bottom edges, missing blocks) and JPEG 2000 (IC = C8, or M8 with a mask)
// through OpenJPEG, decoding only the part of the codestream the region needs. Anything else (JPEG,
// VQ, bi-level, 1- or 12-bit packed samples, NITF 2.0) is refused with what it is.
//
// Pixels: x = column, y = row, (0, 0) the centre of the top-left pixel, as NITF's own row/column numbers
// (and as RPC00B counts them). Integer fields are big-endian in the file and converted here only.
// A file with several image segments (a large image split in segments, an overlay, a thumbnail) is
// refused on reading its pixels, with the segments' sizes: which one is "the image" is not guessed.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tpkit/core/image_io.hpp"

namespace tpkit {

// A tagged record extension: its 6-character tag (CETAG) and its data (CEDATA, CEL bytes); `offset` is
// where its CETAG lies in the file it was read from (0 for one made in memory), for messages.
struct NitfTre {
  std::string tag, data;
  uint64_t offset = 0;
};

// The first image segment of a NITF file, as its subheader describes it.
struct NitfImage {
  std::string path;
  std::string version;   // "NITF02.10" or "NSIF01.00"
  int image_segments = 0;
  long rows = 0, cols = 0;  // NROWS, NCOLS
  int bands = 0;
  std::string irep;      // IREP: MONO, RGB, RGB/LUT, MULTI, ...
  std::string pvtype;    // INT (unsigned), SI (signed), R (real)
  int nbpp = 0;          // bits per sample as stored (8, 16, 32, 64)
  int abpp = 0;          // significant bits (e.g. 11 in 16-bit words)
  char pjust = 'R';      // justification of the ABPP bits in NBPP: R(ight) or L(eft)
  std::string ic;        // compression: NC, NM, C8, M8 (read); anything else refused on reading pixels
  char imode = 'B';      // B (band interleaved by block), P (by pixel), R (by row), S (band sequential)
  long nbpr = 1, nbpc = 1, nppbh = 0, nppbv = 0;  // blocks per row / column, pixels per block
  uint64_t data_offset = 0, data_length = 0;      // the image data in the file (mask tables included)
  std::vector<NitfTre> tres;  // the subheader's UDID and IXSHD TREs, in file order
  bool tre_overflow = false;  // some TREs were moved to a TRE_OVERFLOW DES (not read)
};

// True when the file starts with "NITF" or "NSIF" (a cheap check, no parsing).
bool is_nitf_file(const std::string& path);

// Parses the file header and the first image subheader. InputError(path: reason, with the byte offset
// and field name) for a truncated or malformed file, a NITF version other than 2.1 / NSIF 1.0, or a file
// without images.
NitfImage read_nitf_image(const std::string& path);

// The first TRE with this tag, or nullptr.
const NitfTre* find_nitf_tre(const NitfImage&, const std::string& tag);

// ImageInfo of the first image segment: format "uint8", "uint16", "int16", "uint32", "int32", "float" or
// "double" from NBPP and PVTYPE, bits = ABPP, nodata = the pad pixel value of a masked image when given.
ImageInfo nitf_image_info(const NitfImage&);

// The region [x0, x0 + w) x [y0, y0 + h) of band `band` (0-based), clipped to the image, as float in the
// image's own radiometry. Reads only the blocks (or JPEG 2000 tiles) that cover it.
Raster read_nitf_region(const NitfImage&, int band, long x0, long y0, long w, long h);

// Writes a single-band NITF 2.1 file of unsigned samples of `abpp` bits (at most 16; 8 or fewer are
// stored in bytes, more in 16-bit words), row strip by row strip, atomically (like TiffWriterU16):
// uncompressed (IC = NC, IMODE B, blocks of `block` pixels (or the image's side when smaller), pad pixels
// 0 at the right and bottom) or JPEG 2000 (IC = C8: one lossless codestream, reversible 5-3 wavelet, tiles
// of `block` pixels likewise,
// written tile row by tile row through OpenJPEG), with the given TREs in the image subheader.
struct NitfWriteOptions {
  enum class Compression { none, j2k } compression = Compression::none;
  long block = 1024;
  int abpp = 16;
  std::vector<NitfTre> tres;
};
class NitfWriterU16 {
 public:
  NitfWriterU16(const std::string& path, long width, long height, const NitfWriteOptions& options);
  ~NitfWriterU16();
  // Rows y0 .. y0 + rows - 1, each `width` samples; strips must come in order.
  void write_rows(long y0, long rows, const uint16_t* data);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tpkit
