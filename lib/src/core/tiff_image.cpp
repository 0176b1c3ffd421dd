#include "tpkit/core/tiff_image.hpp"

#include <tiffio.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>

#include "tpkit/core/error.hpp"

namespace tpkit {

namespace {
// libtiff does not define tag 50844 itself: it is registered (as GDAL does) by a tag extender, so that it
// can be written into a file that lacks it and is read with a 32-bit count; the GeoTIFF and GDAL tags
// likewise, where libtiff does not know them.
TIFFExtendProc parent_extender = nullptr;
void tpkit_tag_extender(TIFF* tif) {
  static const TIFFFieldInfo info[] = {{TIFFTAG_RPCCOEFFICIENT, TIFF_VARIABLE2, TIFF_VARIABLE2, TIFF_DOUBLE, FIELD_CUSTOM,
                                        1, 1, const_cast<char*>("RPCCoefficientTag")}};
  TIFFMergeFieldInfo(tif, info, 1);
  static const TIFFFieldInfo geo[] = {
      {33550, -1, -1, TIFF_DOUBLE, FIELD_CUSTOM, 1, 1, const_cast<char*>("ModelPixelScaleTag")},
      {33922, -1, -1, TIFF_DOUBLE, FIELD_CUSTOM, 1, 1, const_cast<char*>("ModelTiepointTag")},
      {34735, -1, -1, TIFF_SHORT, FIELD_CUSTOM, 1, 1, const_cast<char*>("GeoKeyDirectoryTag")},
      {42113, -1, -1, TIFF_ASCII, FIELD_CUSTOM, 1, 0, const_cast<char*>("GDALNoDataTag")}};
  for (const auto& g : geo)
    if (!TIFFFindField(tif, g.field_tag, TIFF_ANY)) TIFFMergeFieldInfo(tif, &g, 1);
  if (parent_extender) parent_extender(tif);
}

// The TIFF closed on every path out.
struct TiffHandle {
  TIFF* tif;
  explicit TiffHandle(TIFF* t) : tif(t) {}
  ~TiffHandle() {
    if (tif) TIFFClose(tif);
  }
};

// What a region read needs to know of the first directory, in libtiff's terms.
struct Layout {
  uint32_t width = 0, height = 0, tile_w = 0, tile_h = 0, rows_per_strip = 0;
  uint16_t spp = 1, bits = 0, format = SAMPLEFORMAT_UINT, planar = PLANARCONFIG_CONTIG, photometric = PHOTOMETRIC_MINISBLACK,
           compression = COMPRESSION_NONE;
  bool tiled = false;
};

Layout layout_of(TIFF* tif) {
  Layout L;
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &L.width);
  TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &L.height);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &L.spp);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &L.bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &L.format);
  if (L.format == SAMPLEFORMAT_VOID) L.format = SAMPLEFORMAT_UINT;  // "untyped": read as unsigned, as OIIO does
  TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &L.planar);
  if (!TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &L.photometric)) L.photometric = L.spp >= 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK;
  TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &L.compression);
  L.tiled = TIFFIsTiled(tif) != 0;
  if (L.tiled) {
    TIFFGetField(tif, TIFFTAG_TILEWIDTH, &L.tile_w);
    TIFFGetField(tif, TIFFTAG_TILELENGTH, &L.tile_h);
  } else {
    TIFFGetFieldDefaulted(tif, TIFFTAG_ROWSPERSTRIP, &L.rows_per_strip);
    L.rows_per_strip = std::min(L.rows_per_strip, std::max<uint32_t>(1, L.height));
  }
  return L;
}

// Sample types and layouts read here; the rest (palette and YCbCr colour, bit-packed, 24-bit or half-float
// samples, old-style JPEG) is OpenImageIO's.
bool handled(const Layout& L) {
  const bool integer = L.format == SAMPLEFORMAT_UINT || L.format == SAMPLEFORMAT_INT;
  const bool ok_bits = integer ? (L.bits == 8 || L.bits == 16 || L.bits == 32) : (L.format == SAMPLEFORMAT_IEEEFP && (L.bits == 32 || L.bits == 64));
  const bool ok_colour = L.photometric == PHOTOMETRIC_MINISBLACK || L.photometric == PHOTOMETRIC_RGB;
  const bool ok_chunks = L.tiled ? (L.tile_w > 0 && L.tile_h > 0) : L.rows_per_strip > 0;
  return ok_bits && ok_colour && ok_chunks && L.spp >= 1 && L.compression != COMPRESSION_OJPEG && L.width > 0 && L.height > 0;
}

std::string type_name(const Layout& L) {
  if (L.format == SAMPLEFORMAT_IEEEFP) return L.bits == 32 ? "float" : "double";
  return std::string(L.format == SAMPLEFORMAT_INT ? "int" : "uint") + std::to_string(L.bits);
}

TIFF* open_tiff(const std::string& path) {
  register_tiff_tags();
  TIFF* tif = TIFFOpen(path.c_str(), "r");
  if (!tif) throw InputError(path, 0, "read error: libtiff cannot open the TIFF (a truncated file, or a corrupt header?)");
  return tif;
}

// Converts n samples, `stride` samples apart, of the chunk's native type to float.
template <class T>
void convert(const unsigned char* src, size_t stride, size_t n, float* dst) {
  for (size_t i = 0; i < n; ++i) {
    T v;
    std::memcpy(&v, src + i * stride * sizeof(T), sizeof(T));
    dst[i] = static_cast<float>(v);
  }
}
using Converter = void (*)(const unsigned char*, size_t, size_t, float*);
Converter converter_for(const Layout& L) {
  if (L.format == SAMPLEFORMAT_IEEEFP) return L.bits == 32 ? convert<float> : convert<double>;
  const bool s = L.format == SAMPLEFORMAT_INT;
  switch (L.bits) {
    case 8: return s ? convert<int8_t> : convert<uint8_t>;
    case 16: return s ? convert<int16_t> : convert<uint16_t>;
    default: return s ? convert<int32_t> : convert<uint32_t>;
  }
}
}  // namespace

void register_tiff_tags() {
  static std::once_flag once;
  std::call_once(once, [] {
    parent_extender = TIFFSetTagExtender(tpkit_tag_extender);
    TIFFSetWarningHandler(nullptr);
    TIFFSetErrorHandler(nullptr);
  });
}

bool is_tiff_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[4];
  if (!in.read(reinterpret_cast<char*>(h), 4)) return false;
  return (h[0] == 'I' && h[1] == 'I' && (h[2] == 42 || h[2] == 43) && h[3] == 0) ||
         (h[0] == 'M' && h[1] == 'M' && h[2] == 0 && (h[3] == 42 || h[3] == 43));
}

std::optional<TiffTagEntry> tiff_first_ifd_tag(const std::string& path, uint16_t tag) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[16];
  if (!in.read(reinterpret_cast<char*>(h), 16)) return std::nullopt;
  const bool le = h[0] == 'I';
  auto u = [&](const unsigned char* p, int n) {
    uint64_t v = 0;
    for (int k = 0; k < n; ++k) v |= uint64_t(p[le ? k : n - 1 - k]) << (8 * k);
    return v;
  };
  const uint64_t magic = u(h + 2, 2);
  if (magic != 42 && magic != 43) return std::nullopt;
  const bool big = magic == 43;
  const uint64_t ifd = big ? u(h + 8, 8) : u(h + 4, 4);
  const int count_size = big ? 8 : 2, entry_size = big ? 20 : 12, value_size = big ? 8 : 4;
  unsigned char c[8];
  if (!in.seekg(static_cast<std::streamoff>(ifd)) || !in.read(reinterpret_cast<char*>(c), count_size)) return std::nullopt;
  const uint64_t n = u(c, count_size);
  for (uint64_t e = 0; e < n && e < 65536; ++e) {
    unsigned char d[20];
    if (!in.read(reinterpret_cast<char*>(d), entry_size)) return std::nullopt;
    if (u(d, 2) != tag) continue;
    TiffTagEntry t;
    t.type = static_cast<int>(u(d + 2, 2));
    t.count = u(d + 4, big ? 8 : 4);
    // bytes per value of TIFF 6 and BigTIFF's types 1 .. 18
    static const int kTypeBytes[19] = {0, 1, 1, 2, 4, 8, 1, 1, 2, 4, 8, 4, 8, 4, 0, 0, 8, 8, 8};
    const uint64_t size = t.type >= 1 && t.type <= 18 ? static_cast<uint64_t>(kTypeBytes[t.type]) : 0;
    t.bytes = size == 0 ? 0 : t.count <= UINT64_MAX / size ? t.count * size : UINT64_MAX;
    const uint64_t entry_at = ifd + count_size + e * entry_size;
    t.offset = t.bytes <= static_cast<uint64_t>(value_size) ? entry_at + entry_size - value_size  // in the entry
                                                            : u(d + entry_size - value_size, value_size);
    return t;
  }
  return std::nullopt;
}

std::optional<ImageInfo> tiff_image_info(const std::string& path) {
  TiffHandle t(open_tiff(path));
  const Layout L = layout_of(t.tif);
  if (!handled(L)) return std::nullopt;
  ImageInfo info;
  info.path = path;
  info.width = L.width;
  info.height = L.height;
  info.bands = L.spp;
  info.format = type_name(L);
  info.bits = L.bits;
  info.rgb = L.photometric == PHOTOMETRIC_RGB && L.spp >= 3;
  char* nd = nullptr;
  if (TIFFGetField(t.tif, 42113, &nd) && nd) {
    char* end = nullptr;
    const double v = std::strtod(nd, &end);
    if (end != nd) info.nodata = v;
  }
  return info;
}

std::optional<Raster> read_tiff_region(const std::string& path, int band, long x0, long y0, long w, long h, Raster reuse) {
  auto r = read_tiff_bands(path, {band}, x0, y0, w, h, std::move(reuse));
  if (!r) return std::nullopt;
  return std::move(r->front());
}

std::optional<std::vector<Raster>> read_tiff_bands(const std::string& path, const std::vector<int>& bands, long x0, long y0, long w,
                                                   long h, Raster reuse) {
  TiffHandle t(open_tiff(path));
  TIFF* tif = t.tif;
  const Layout L = layout_of(tif);
  if (!handled(L)) return std::nullopt;
  // Chunk geometry: a contiguous chunk interleaves the bands (stride spp), a separate one holds one band.
  const bool contig = L.planar == PLANARCONFIG_CONTIG;
  if (!contig && bands.size() > 1) {  // separate planes: one band's chunks hold nothing of another's
    std::vector<Raster> out;
    for (size_t j = 0; j < bands.size(); ++j)
      out.push_back(*read_tiff_region(path, bands[j], x0, y0, w, h, j == 0 ? std::move(reuse) : Raster()));
    return out;
  }
  // every branch below writes every sample of the region in every band asked for (or throws)
  std::vector<Raster> out;
  for (size_t j = 0; j < bands.size(); ++j)
    out.push_back(clipped_raster(path, L.width, L.height, L.spp, bands[j], x0, y0, w, h, j == 0 ? std::move(reuse) : Raster()));
  const Raster& r = out.front();
  if (r.data.empty()) return out;
  const long xa = r.x0, ya = r.y0, xb = r.x0 + r.width, yb = r.y0 + r.height;

  const size_t bps = L.bits / 8, stride = contig ? L.spp : 1, pixel_bytes = bps * stride;
  const uint16_t plane = contig ? 0 : static_cast<uint16_t>(bands.front());
  const Converter to_float = converter_for(L);
  // n pixels of a decoded chunk from `px` on, into the samples out[j].data[at ...] of each band asked for
  auto put = [&](const unsigned char* px, size_t n, size_t at) {
    for (size_t j = 0; j < bands.size(); ++j)
      to_float(px + (contig ? static_cast<size_t>(bands[j]) * bps : 0), stride, n, out[j].data.data() + at);
  };
  std::error_code ec;
  const uint64_t file_bytes = std::filesystem::file_size(path, ec);
  const uint32_t chunks = L.tiled ? TIFFNumberOfTiles(tif) : TIFFNumberOfStrips(tif);
  // A header may declare more samples than the file holds (25 000 x 25 000 floats in 550 bytes): every
  // chunk read must lie in the file, before anything its size is allocated.
  auto check_chunk = [&](uint32_t c, const std::string& what) {
    if (c >= chunks) throw InputError(path, 0, "the header declares " + std::to_string(chunks) + " " + what + "s, the image needs more");
    const uint64_t off = TIFFGetStrileOffset(tif, c), len = TIFFGetStrileByteCount(tif, c);
    if (ec || off > file_bytes || len > file_bytes - off)
      throw InputError(path, 0, what + " " + std::to_string(c) + " lies beyond the end of the file (" + std::to_string(file_bytes) +
                                    " bytes): a truncated file, or a header declaring more samples than the file holds");
    return std::make_pair(off, len);
  };
  constexpr tmsize_t kMaxChunkBytes = tmsize_t(1) << 30;

  if (!L.tiled && L.compression == COMPRESSION_NONE) {
    // uncompressed strips: only the rows asked for are read, straight from the file
    const size_t row_bytes = static_cast<size_t>(L.width) * pixel_bytes;
    const uint32_t strips_per_plane = (L.height + L.rows_per_strip - 1) / L.rows_per_strip;
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> buf(static_cast<size_t>(r.width) * pixel_bytes);
    for (long y = ya; y < yb; ++y) {
      const uint32_t strip = static_cast<uint32_t>(y / L.rows_per_strip) + plane * strips_per_plane;
      const auto [off, len] = check_chunk(strip, "strip");
      const uint64_t at = static_cast<uint64_t>(y % L.rows_per_strip) * row_bytes + static_cast<uint64_t>(xa) * pixel_bytes;
      if (at + buf.size() > len) throw InputError(path, 0, "strip " + std::to_string(strip) + " is short (truncated file?)");
      in.seekg(static_cast<std::streamoff>(off + at));
      if (!in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(buf.size())))
        throw InputError(path, 0, "read error at row " + std::to_string(y));
      if (TIFFIsByteSwapped(tif)) {
        const tmsize_t n = static_cast<tmsize_t>(buf.size() / bps);
        if (bps == 2) TIFFSwabArrayOfShort(reinterpret_cast<uint16_t*>(buf.data()), n);
        else if (bps == 4) TIFFSwabArrayOfLong(reinterpret_cast<uint32_t*>(buf.data()), n);
        else if (bps == 8) TIFFSwabArrayOfDouble(reinterpret_cast<double*>(buf.data()), n);
      }
      put(buf.data(), static_cast<size_t>(r.width), static_cast<size_t>(y - ya) * r.width);
    }
    return out;
  }

  if (!L.tiled) {
    // compressed strips: each strip that meets the rows is decoded whole (libtiff swaps the bytes)
    const tmsize_t strip_bytes = TIFFStripSize(tif);
    if (strip_bytes <= 0 || strip_bytes > kMaxChunkBytes)
      throw InputError(path, 0, "a compressed strip of " + std::to_string(strip_bytes >> 20) + " MiB decoded: larger than 1 GiB (write the file tiled)");
    const size_t row_bytes = static_cast<size_t>(L.width) * pixel_bytes;
    std::vector<unsigned char> buf(static_cast<size_t>(strip_bytes));
    for (long s = ya / L.rows_per_strip; s * static_cast<long>(L.rows_per_strip) < yb; ++s) {
      const uint32_t strip = TIFFComputeStrip(tif, static_cast<uint32_t>(s * L.rows_per_strip), plane);
      check_chunk(strip, "strip");
      const tmsize_t n = TIFFReadEncodedStrip(tif, strip, buf.data(), strip_bytes);
      if (n < 0) throw InputError(path, 0, "read error: strip " + std::to_string(strip) + " cannot be decoded (truncated or corrupt file?)");
      const long row0 = s * static_cast<long>(L.rows_per_strip), rows = static_cast<long>(static_cast<size_t>(n) / row_bytes);
      if (row0 + rows < std::min<long>(yb, row0 + L.rows_per_strip))
        throw InputError(path, 0, "read error: strip " + std::to_string(strip) + " is short (truncated file?)");
      for (long y = std::max(ya, row0); y < std::min(yb, row0 + rows); ++y)
        put(buf.data() + static_cast<size_t>(y - row0) * row_bytes + static_cast<size_t>(xa) * pixel_bytes, static_cast<size_t>(r.width),
            static_cast<size_t>(y - ya) * r.width);
    }
    return out;
  }

  // tiles: each tile that meets the region is decoded whole
  const tmsize_t tile_bytes = TIFFTileSize(tif);
  if (tile_bytes <= 0 || tile_bytes > kMaxChunkBytes)
    throw InputError(path, 0, "a tile of " + std::to_string(tile_bytes >> 20) + " MiB decoded: larger than 1 GiB");
  const long tw = L.tile_w, th = L.tile_h;
  const size_t tile_row_bytes = static_cast<size_t>(tw) * pixel_bytes;
  std::vector<unsigned char> buf(static_cast<size_t>(tile_bytes));
  for (long ty = (ya / th) * th; ty < yb; ty += th)
    for (long tx = (xa / tw) * tw; tx < xb; tx += tw) {
      const uint32_t tile = TIFFComputeTile(tif, static_cast<uint32_t>(tx), static_cast<uint32_t>(ty), 0, plane);
      check_chunk(tile, "tile");
      if (TIFFReadEncodedTile(tif, tile, buf.data(), tile_bytes) < 0)
        throw InputError(path, 0, "read error: tile " + std::to_string(tile) + " cannot be decoded (truncated or corrupt file?)");
      const long cx0 = std::max(xa, tx), cx1 = std::min(xb, tx + tw);
      for (long y = std::max(ya, ty); y < std::min(yb, ty + th); ++y)
        put(buf.data() + static_cast<size_t>(y - ty) * tile_row_bytes + static_cast<size_t>(cx0 - tx) * pixel_bytes,
            static_cast<size_t>(cx1 - cx0), static_cast<size_t>(y - ya) * r.width + (cx0 - xa));
    }
  return out;
}

TiffRowWriter::TiffRowWriter(const std::string& path, long width, long height, int bits, int zip_level,
                             const std::vector<std::pair<std::string, std::string>>& tags)
    : path_(path), width_(width), height_(height), bits_(bits) {
  if (bits != 8 && bits != 16) throw std::logic_error("TiffRowWriter: 8 or 16 bits");
  static const std::map<std::string, uint32_t> kAscii = {{"ImageDescription", TIFFTAG_IMAGEDESCRIPTION}, {"DateTime", TIFFTAG_DATETIME},
                                                         {"Software", TIFFTAG_SOFTWARE}, {"Artist", TIFFTAG_ARTIST},
                                                         {"Copyright", TIFFTAG_COPYRIGHT}, {"DocumentName", TIFFTAG_DOCUMENTNAME}};
  for (const auto& kv : tags)
    if (!kAscii.count(kv.first)) throw std::logic_error("TiffRowWriter: unknown tag " + kv.first);
  register_tiff_tags();
  // BigTIFF only when the samples alone could pass the 4 GiB of a classic TIFF
  const bool big = static_cast<double>(width) * height * (bits / 8) > 3.5e9;
  TIFF* tif = TIFFOpen(path.c_str(), big ? "w8" : "w");
  if (!tif) throw InputError(path, 0, "cannot create");
  tif_ = tif;
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, static_cast<uint32_t>(width));
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, static_cast<uint32_t>(height));
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, bits);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_UINT);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  TIFFSetField(tif, TIFFTAG_ZIPQUALITY, zip_level);
  TIFFSetField(tif, TIFFTAG_PREDICTOR, PREDICTOR_HORIZONTAL);
  TIFFSetField(tif, TIFFTAG_TILEWIDTH, static_cast<uint32_t>(kTile));
  TIFFSetField(tif, TIFFTAG_TILELENGTH, static_cast<uint32_t>(kTile));
  for (const auto& kv : tags) TIFFSetField(tif, kAscii.at(kv.first), kv.second.c_str());
}

TiffRowWriter::~TiffRowWriter() {
  if (tif_) TIFFClose(static_cast<TIFF*>(tif_));
}

void TiffRowWriter::write_rows(long rows, const void* data) {
  if (!tif_ || next_ + rows > height_) throw std::logic_error("TiffRowWriter: rows past the image or after close");
  const size_t bytes = static_cast<size_t>(bits_ / 8), row_bytes = static_cast<size_t>(width_) * bytes;
  // rows gather into one row of tiles, written when it is full (or the image ends)
  band_.resize(row_bytes * kTile);
  for (long k = 0; k < rows; ++k, ++next_) {
    std::memcpy(band_.data() + static_cast<size_t>(next_ % kTile) * row_bytes, static_cast<const unsigned char*>(data) + k * row_bytes, row_bytes);
    if ((next_ + 1) % kTile == 0 || next_ + 1 == height_) write_tile_row();
  }
}

// The tile row that holds row next_: each tile copied out of the band (the predictor differences the
// tile in place, and an edge tile is padded with zeros), then compressed and written.
void TiffRowWriter::write_tile_row() {
  TIFF* tif = static_cast<TIFF*>(tif_);
  const size_t bytes = static_cast<size_t>(bits_ / 8), row_bytes = static_cast<size_t>(width_) * bytes;
  const long y0 = next_ - next_ % kTile, rows = next_ + 1 - y0;
  tile_.resize(static_cast<size_t>(kTile) * kTile * bytes);
  for (long x0 = 0; x0 < width_; x0 += kTile) {
    const size_t cols = static_cast<size_t>(std::min<long>(kTile, width_ - x0)) * bytes;
    std::fill(tile_.begin(), tile_.end(), 0);
    for (long r = 0; r < rows; ++r)
      std::memcpy(tile_.data() + static_cast<size_t>(r) * kTile * bytes, band_.data() + static_cast<size_t>(r) * row_bytes + static_cast<size_t>(x0) * bytes, cols);
    const uint32_t index = TIFFComputeTile(tif, static_cast<uint32_t>(x0), static_cast<uint32_t>(y0), 0, 0);
    if (TIFFWriteEncodedTile(tif, index, tile_.data(), static_cast<tmsize_t>(tile_.size())) < 0)
      throw InputError(path_, 0, "write error at rows " + std::to_string(y0) + "-" + std::to_string(y0 + rows - 1) + " (disk full?)");
  }
}

void TiffRowWriter::set_rpc_tag(const std::array<double, 92>& values) {
  if (!tif_ || !TIFFSetField(static_cast<TIFF*>(tif_), TIFFTAG_RPCCOEFFICIENT, static_cast<uint32_t>(92), values.data()))
    throw InputError(path_, 0, "cannot set RPC tag 50844");
}

bool TiffRowWriter::close() {
  TIFF* tif = static_cast<TIFF*>(tif_);
  if (!tif) return false;
  tif_ = nullptr;
  const bool ok = next_ == height_ && TIFFFlush(tif) == 1;
  TIFFClose(tif);
  return ok;
}

}  // namespace tpkit
