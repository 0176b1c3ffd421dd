// See nitf_image.hpp. Field names and lengths are MIL-STD-2500C's (NITF 2.1), table A-1 (file header)
// and A-3 (image subheader); the block mask of IC = NM / M8 is its table A-3(A).
#include "tpkit/core/nitf_image.hpp"

#include <openjpeg.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"

namespace tpkit {

namespace {

// ---------------------------------------------------------------- reading bytes

// A read-only file with positioned reads; every short read is "truncated" with the offset.
class ByteFile {
 public:
  explicit ByteFile(const std::string& path) : path_(path) {
    check_input_file(path, InputKind::image);
    note_input(path);
    f_ = std::fopen(path.c_str(), "rb");
    if (!f_) throw InputError(path, 0, std::string("cannot open for reading: ") + std::strerror(errno));
    struct stat st {};
    if (fstat(fileno(f_), &st) == 0) size_ = static_cast<uint64_t>(st.st_size);
  }
  ~ByteFile() {
    if (f_) std::fclose(f_);
  }
  ByteFile(const ByteFile&) = delete;
  ByteFile& operator=(const ByteFile&) = delete;
  uint64_t size() const { return size_; }
  FILE* handle() const { return f_; }
  void read(uint64_t offset, void* dst, size_t n, const char* what) const {
    if (offset + n > size_ || fseeko(f_, static_cast<off_t>(offset), SEEK_SET) != 0 || std::fread(dst, 1, n, f_) != n)
      throw InputError(path_, 0, std::string("truncated: ") + what + " (bytes " + std::to_string(offset) + " to " +
                                     std::to_string(offset + n) + ") beyond the end of the file (" + std::to_string(size_) +
                                     " bytes)");
  }
  std::string read_string(uint64_t offset, size_t n, const char* what) const {
    std::string s(n, '\0');
    read(offset, s.data(), n, what);
    return s;
  }

 private:
  std::string path_;
  FILE* f_ = nullptr;
  uint64_t size_ = 0;
};

// Fields of a header read in order, each by its MIL-STD-2500C name; errors name the field and offset.
class FieldCursor {
 public:
  FieldCursor(const std::string& path, const std::string& bytes, uint64_t file_offset)
      : path_(path), b_(bytes), base_(file_offset) {}
  std::string text(size_t n, const char* name) {
    if (pos_ + n > b_.size())
      throw InputError(path_, 0, std::string("truncated header: field ") + name + " at byte " + std::to_string(base_ + pos_) +
                                     " runs past the header's end");
    std::string s = b_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::string trimmed(size_t n, const char* name) {
    std::string s = text(n, name);
    size_t a = s.find_first_not_of(' '), e = s.find_last_not_of(' ');
    return a == std::string::npos ? std::string() : s.substr(a, e - a + 1);
  }
  // An unsigned decimal field (all digits).
  uint64_t number(size_t n, const char* name) {
    const uint64_t at = base_ + pos_;
    std::string s = text(n, name);
    if (s.empty() || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw InputError(path_, 0, std::string("field ") + name + " at byte " + std::to_string(at) + " is '" + printable(s) +
                                     "', not a number");
    return std::stoull(s);
  }
  void skip(size_t n, const char* name) { text(n, name); }
  size_t pos() const { return pos_; }
  uint64_t file_offset() const { return base_ + pos_; }
  static std::string printable(const std::string& s) {
    std::string o;
    for (char c : s) o += (c >= 32 && c < 127) ? c : '?';
    return o;
  }

 private:
  const std::string& path_;
  const std::string& b_;
  uint64_t base_;
  size_t pos_ = 0;
};

constexpr size_t kSecurityFields = 167;  // xSCLAS .. xSCTLN of NITF 2.1 (the file's and each segment's)

// TREs of a UDID or IXSHD area (CETAG 6, CEL 5, CEDATA).
void parse_tres(const std::string& path, const std::string& area, uint64_t offset, std::vector<NitfTre>& out) {
  FieldCursor c(path, area, offset);
  while (c.pos() < area.size()) {
    NitfTre t;
    t.offset = c.file_offset();
    t.tag = c.trimmed(6, "CETAG");
    const uint64_t len = c.number(5, "CEL");
    t.data = c.text(static_cast<size_t>(len), "CEDATA");
    out.push_back(std::move(t));
  }
}

// ---------------------------------------------------------------- the image segment's layout

int bytes_per_sample(const NitfImage& im) { return im.nbpp / 8; }

bool masked(const NitfImage& im) { return im.ic == "NM" || im.ic == "M8"; }

// Where each block starts (relative to the file): from the block mask of NM / M8, or one after the
// other for NC; UINT64_MAX for a block that is not in the file. Index: block (row-major), and for IMODE
// S band * blocks + block. Also the pad pixel value when the mask gives one.
struct BlockMap {
  std::vector<uint32_t> table;  // the mask's block offsets (from `first`), when it has them
  std::optional<double> pad;
  uint64_t first = 0;  // where the blocks (or the codestream) begin
  uint64_t block_bytes = 0;
  uint64_t start(uint64_t k) const {
    if (table.empty()) return first + k * block_bytes;
    return table[k] == 0xFFFFFFFFu ? UINT64_MAX : first + table[k];
  }
};

BlockMap read_block_map(const ByteFile& f, const NitfImage& im) {
  BlockMap m;
  const uint64_t nblocks = static_cast<uint64_t>(im.nbpr) * im.nbpc;
  const uint64_t entries = im.imode == 'S' ? nblocks * im.bands : nblocks;
  m.block_bytes = static_cast<uint64_t>(im.nppbh) * im.nppbv * bytes_per_sample(im) * (im.imode == 'S' ? 1 : im.bands);
  m.first = im.data_offset;
  const uint64_t end = im.data_offset + im.data_length;
  if (masked(im)) {
    unsigned char h[10];
    f.read(im.data_offset, h, sizeof h, "the block mask header");
    auto be = [](const unsigned char* p, int n) {
      uint64_t v = 0;
      for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
      return v;
    };
    const uint64_t imdatoff = be(h, 4), bmrlnth = be(h + 4, 2), tmrlnth = be(h + 6, 2), tpxcdlnth = be(h + 8, 2);
    uint64_t pos = im.data_offset + 10;
    if (tpxcdlnth > 0) {
      const size_t n = static_cast<size_t>((tpxcdlnth + 7) / 8);
      if (n > 8) throw InputError(im.path, 0, "pad pixel code of " + std::to_string(tpxcdlnth) + " bits");
      unsigned char p[8];
      f.read(pos, p, n, "the pad pixel code");
      m.pad = static_cast<double>(be(p, static_cast<int>(n)));
      pos += n;
    }
    if (bmrlnth != 0 && bmrlnth != 4) throw InputError(im.path, 0, "block mask records of " + std::to_string(bmrlnth) + " bytes (4 expected)");
    if (tmrlnth != 0 && tmrlnth != 4) throw InputError(im.path, 0, "pad pixel mask records of " + std::to_string(tmrlnth) + " bytes (4 expected)");
    if (imdatoff >= im.data_length) throw InputError(im.path, 0, "block mask: IMDATOFF " + std::to_string(imdatoff) + " is past the image data");
    m.first = im.data_offset + imdatoff;
    if (bmrlnth == 4) {
      if (entries > (end - pos) / 4)
        throw InputError(im.path, 0, "truncated: a block mask of " + std::to_string(entries) + " records does not fit the image data");
      std::vector<unsigned char> raw(static_cast<size_t>(entries) * 4);
      f.read(pos, raw.data(), raw.size(), "the block mask");
      m.table.resize(entries);
      for (uint64_t k = 0; k < entries; ++k) {
        m.table[k] = static_cast<uint32_t>(be(raw.data() + 4 * k, 4));
        if (m.table[k] != 0xFFFFFFFFu && (im.ic == "NM" && m.start(k) + m.block_bytes > end))
          throw InputError(im.path, 0, "truncated: block " + std::to_string(k) + " ends past the image data (" +
                                           std::to_string(im.data_length) + " bytes)");
      }
      return m;
    }
  }
  if ((im.ic == "NC" || im.ic == "NM") && (m.block_bytes == 0 || entries > (end - m.first) / m.block_bytes))
    throw InputError(im.path, 0, "truncated: " + std::to_string(entries) + " blocks of " + std::to_string(m.block_bytes) +
                                     " bytes do not fit the image data (" + std::to_string(im.data_length) + " bytes)");
  return m;
}

// One big-endian sample as float, its ABPP bits taken from where PJUST puts them.
float sample_value(const NitfImage& im, const unsigned char* p) {
  const int shift = im.pjust == 'L' ? im.nbpp - im.abpp : 0;
  switch (im.nbpp) {
    case 8: return im.pvtype == "SI" ? static_cast<float>(static_cast<int8_t>(p[0]) >> shift) : static_cast<float>(p[0] >> shift);
    case 16: {
      const uint16_t u = static_cast<uint16_t>((p[0] << 8) | p[1]);
      return im.pvtype == "SI" ? static_cast<float>(static_cast<int16_t>(u) >> shift) : static_cast<float>(u >> shift);
    }
    case 32: {
      const uint32_t u = (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3];
      if (im.pvtype == "R") {
        float v;
        std::memcpy(&v, &u, 4);
        return v;
      }
      return im.pvtype == "SI" ? static_cast<float>(static_cast<int32_t>(u) >> shift) : static_cast<float>(u >> shift);
    }
    default: {  // 64: real
      uint64_t u = 0;
      for (int i = 0; i < 8; ++i) u = (u << 8) | p[i];
      double v;
      std::memcpy(&v, &u, 8);
      return static_cast<float>(v);
    }
  }
}

void check_readable(const NitfImage& im) {
  if (im.image_segments > 1)
    throw InputError(im.path, 0, std::to_string(im.image_segments) + " image segments (the first " + std::to_string(im.cols) + " x " +
                                     std::to_string(im.rows) + "): only files with one image segment are read");
  if (im.ic != "NC" && im.ic != "NM" && im.ic != "C8" && im.ic != "M8")
    throw InputError(im.path, 0, "compression IC=" + im.ic +
                                     " is not supported (uncompressed NC/NM and JPEG 2000 C8/M8 are; C3/M3 is JPEG, C4/M4 VQ, C1 bi-level)");
  if (im.nbpp != 8 && im.nbpp != 16 && im.nbpp != 32 && im.nbpp != 64)
    throw InputError(im.path, 0, "NBPP=" + std::to_string(im.nbpp) + ": packed samples are not supported (8, 16, 32 or 64 bits are)");
  if (im.pvtype != "INT" && im.pvtype != "SI" && im.pvtype != "R")
    throw InputError(im.path, 0, "PVTYPE=" + im.pvtype + " is not supported (INT, SI and R are)");
  if ((im.pvtype == "R" && im.nbpp < 32) || (im.nbpp == 64 && im.pvtype != "R"))
    throw InputError(im.path, 0, "PVTYPE=" + im.pvtype + " with NBPP=" + std::to_string(im.nbpp) + " is not a sample type");
}

// ---------------------------------------------------------------- uncompressed pixels

// Byte offset of sample (band, column bx, row by inside the block) from the block's start, for each
// IMODE; for S the block start is already the band's.
uint64_t offset_in_block(const NitfImage& im, int band, long bx, long by) {
  const uint64_t s = static_cast<uint64_t>(bytes_per_sample(im)), w = static_cast<uint64_t>(im.nppbh);
  const uint64_t plane = w * static_cast<uint64_t>(im.nppbv) * s;
  switch (im.imode) {
    case 'P': return ((static_cast<uint64_t>(by) * w + bx) * im.bands + band) * s;
    case 'R': return ((static_cast<uint64_t>(by) * im.bands + band) * w + bx) * s;
    case 'S': return (static_cast<uint64_t>(by) * w + bx) * s;
    default: return band * plane + (static_cast<uint64_t>(by) * w + bx) * s;  // B
  }
}

void read_uncompressed(const ByteFile& f, const NitfImage& im, int band, Raster& r) {
  const BlockMap map = read_block_map(f, im);
  const long xb = r.x0 + r.width, yb = r.y0 + r.height;
  const int s = bytes_per_sample(im);
  const long step = im.imode == 'P' ? im.bands : 1;  // samples between two columns of one band
  const uint64_t nblocks = static_cast<uint64_t>(im.nbpr) * im.nbpc;
  std::vector<unsigned char> row;
  for (long br = r.y0 / im.nppbv; br <= (yb - 1) / im.nppbv; ++br)
    for (long bc = r.x0 / im.nppbh; bc <= (xb - 1) / im.nppbh; ++bc) {
      const uint64_t k = static_cast<uint64_t>(br) * im.nbpr + bc;
      const uint64_t start = map.start(im.imode == 'S' ? band * nblocks + k : k);
      const long xa = std::max(r.x0, bc * im.nppbh), xe = std::min(xb, (bc + 1) * im.nppbh);
      const long ya = std::max(r.y0, br * im.nppbv), ye = std::min(yb, (br + 1) * im.nppbv);
      const size_t n = static_cast<size_t>(xe - xa);
      for (long y = ya; y < ye; ++y) {
        float* dst = r.data.data() + static_cast<size_t>(y - r.y0) * r.width + (xa - r.x0);
        if (start == UINT64_MAX) {  // a block not in the file: pad pixels
          std::fill(dst, dst + n, static_cast<float>(map.pad.value_or(0.0)));
          continue;
        }
        row.resize((n - 1) * step * s + s);
        f.read(start + offset_in_block(im, band, xa - bc * im.nppbh, y - br * im.nppbv), row.data(), row.size(), "a block row");
        for (size_t i = 0; i < n; ++i) dst[i] = sample_value(im, row.data() + i * step * s);
      }
    }
}

// ---------------------------------------------------------------- JPEG 2000 through OpenJPEG

// An OpenJPEG stream over [base, base + length) of an open file.
struct FileSpan {
  FILE* f;
  uint64_t base, length, pos;
};

OPJ_SIZE_T span_read(void* buf, OPJ_SIZE_T n, void* user) {
  auto* s = static_cast<FileSpan*>(user);
  if (s->pos >= s->length) return static_cast<OPJ_SIZE_T>(-1);
  n = static_cast<OPJ_SIZE_T>(std::min<uint64_t>(n, s->length - s->pos));
  if (fseeko(s->f, static_cast<off_t>(s->base + s->pos), SEEK_SET) != 0) return static_cast<OPJ_SIZE_T>(-1);
  const size_t got = std::fread(buf, 1, n, s->f);
  s->pos += got;
  return got == 0 ? static_cast<OPJ_SIZE_T>(-1) : got;
}
OPJ_OFF_T span_skip(OPJ_OFF_T n, void* user) {
  auto* s = static_cast<FileSpan*>(user);
  const int64_t to = static_cast<int64_t>(s->pos) + n;
  if (to < 0) return -1;
  s->pos = static_cast<uint64_t>(to);
  return n;
}
OPJ_BOOL span_seek(OPJ_OFF_T to, void* user) {
  auto* s = static_cast<FileSpan*>(user);
  if (to < 0 || static_cast<uint64_t>(to) > s->length) return OPJ_FALSE;
  s->pos = static_cast<uint64_t>(to);
  return OPJ_TRUE;
}
OPJ_SIZE_T span_write(void* buf, OPJ_SIZE_T n, void* user) {
  auto* s = static_cast<FileSpan*>(user);
  if (fseeko(s->f, static_cast<off_t>(s->base + s->pos), SEEK_SET) != 0) return static_cast<OPJ_SIZE_T>(-1);
  const size_t put = std::fwrite(buf, 1, n, s->f);
  s->pos += put;
  s->length = std::max(s->length, s->pos);
  return put == n ? put : static_cast<OPJ_SIZE_T>(-1);
}

// OpenJPEG's first error message, kept for the InputError.
void keep_first_message(const char* msg, void* user) {
  auto* m = static_cast<std::string*>(user);
  if (m->empty() && msg) {
    *m = msg;
    while (!m->empty() && (m->back() == '\n' || m->back() == '\r')) m->pop_back();
  }
}
void ignore_message(const char*, void*) {}

struct OpjHandles {
  opj_codec_t* codec = nullptr;
  opj_stream_t* stream = nullptr;
  opj_image_t* image = nullptr;
  ~OpjHandles() { reset(); }
  void reset() {
    if (image) opj_image_destroy(image);
    if (stream) opj_stream_destroy(stream);
    if (codec) opj_destroy_codec(codec);
    image = nullptr;
    stream = nullptr;
    codec = nullptr;
  }
};

opj_stream_t* make_stream(FileSpan* span, bool input) {
  opj_stream_t* st = opj_stream_create(size_t(1) << 20, input ? OPJ_TRUE : OPJ_FALSE);
  opj_stream_set_user_data(st, span, nullptr);
  opj_stream_set_user_data_length(st, span->length);
  if (input)
    opj_stream_set_read_function(st, span_read);
  else
    opj_stream_set_write_function(st, span_write);
  opj_stream_set_skip_function(st, span_skip);
  opj_stream_set_seek_function(st, span_seek);
  return st;
}

// Where the codestream starts in `span`: at 0, or in a JP2 file the data of its jp2c box.
uint64_t codestream_start(const ByteFile& f, const NitfImage& im, const FileSpan& span, bool jp2) {
  uint64_t p = 0;
  while (jp2) {
    unsigned char b[16];
    if (p + 8 > span.length) throw InputError(im.path, 0, "JPEG 2000: a JP2 file without a codestream box (jp2c)");
    f.read(span.base + p, b, std::min<uint64_t>(16, span.length - p), "a JP2 box header");
    uint64_t length = (uint64_t(b[0]) << 24) | (uint64_t(b[1]) << 16) | (uint64_t(b[2]) << 8) | b[3], header = 8;
    if (length == 1) {
      length = 0;
      for (int k = 8; k < 16; ++k) length = (length << 8) | b[k];
      header = 16;
    }
    if (std::memcmp(b + 4, "jp2c", 4) == 0) return p + header;
    if (length < header)
      throw InputError(im.path, 0, "JPEG 2000: a JP2 box of " + std::to_string(length) + " bytes at byte " + std::to_string(span.base + p));
    p += length;
  }
  return p;
}

// The first tile-part (SOT marker) of the codestream at `soc`: after SOC, the main header's marker
// segments (each FFxx then its length) up to the first SOT.
uint64_t first_tile_part(const ByteFile& f, const NitfImage& im, const FileSpan& span, uint64_t soc) {
  for (uint64_t p = soc + 2; p + 4 <= span.length;) {
    unsigned char m[4];
    f.read(span.base + p, m, 4, "a JPEG 2000 marker");
    if (m[0] != 0xFF) break;
    if (m[1] == 0x90) return p;
    p += 2 + ((uint64_t(m[2]) << 8) | m[3]);
  }
  throw InputError(im.path, 0, "JPEG 2000: the main header of the codestream at byte " + std::to_string(span.base + soc) +
                                   " leads to no tile-part");
}

// The tile grid of a codestream from its SIZ marker segment, which follows SOC (at `soc` in `span`):
// XTsiz YTsiz the tile size, XTOsiz YTOsiz the grid's origin, Xsiz Ysiz the image's far corner; at most
// 65535 tiles (Isot's 16 bits).
struct TileGrid {
  uint64_t width, height, x0, y0, across, down;
};
TileGrid codestream_tile_grid(const ByteFile& f, const NitfImage& im, const FileSpan& span, uint64_t soc) {
  unsigned char b[40];
  f.read(span.base + soc, b, sizeof b, "the JPEG 2000 SIZ marker");
  auto be32 = [&](int at) { return (uint64_t(b[at]) << 24) | (uint64_t(b[at + 1]) << 16) | (uint64_t(b[at + 2]) << 8) | b[at + 3]; };
  TileGrid g{be32(24), be32(28), be32(32), be32(36), 0, 0};
  if (b[2] != 0xFF || b[3] != 0x51 || g.width == 0 || g.height == 0 || be32(8) <= g.x0 || be32(12) <= g.y0)
    throw InputError(im.path, 0, "JPEG 2000: no valid SIZ marker after SOC at byte " + std::to_string(span.base + soc));
  g.across = (be32(8) - g.x0 + g.width - 1) / g.width;
  g.down = (be32(12) - g.y0 + g.height - 1) / g.height;
  if (g.across * g.down > 65535)
    throw InputError(im.path, 0, "JPEG 2000: " + std::to_string(g.across) + " x " + std::to_string(g.down) + " tiles (65535 at most)");
  return g;
}

// Which tiles the codestream holds: its tile-parts walked from the first SOT marker (`first`, an offset in
// `span`) to EOC (SOT: Lsot, Isot the tile, Psot the tile-part's length, 0 for the last one, which runs to
// EOC). OpenJPEG decodes a tile that is not there as zeros, without a word, when a region also meets tiles
// that are.
std::vector<bool> codestream_tiles(const ByteFile& f, const NitfImage& im, const FileSpan& span, uint64_t first, uint64_t tiles) {
  std::vector<bool> present(tiles, false);
  for (uint64_t p = first; p + 2 <= span.length;) {
    unsigned char m[12] = {};
    f.read(span.base + p, m, std::min<uint64_t>(sizeof m, span.length - p), "a JPEG 2000 tile-part header");
    if (m[0] == 0xFF && m[1] == 0xD9) break;  // EOC
    const uint64_t isot = (uint64_t(m[4]) << 8) | m[5];
    const uint64_t psot = (uint64_t(m[6]) << 24) | (uint64_t(m[7]) << 16) | (uint64_t(m[8]) << 8) | m[9];
    if (m[0] != 0xFF || m[1] != 0x90 || p + 12 > span.length || isot >= tiles)
      throw InputError(im.path, 0, "JPEG 2000: no tile-part header (SOT marker of a tile below " + std::to_string(tiles) +
                                       ") at byte " + std::to_string(span.base + p) + ": a corrupt codestream");
    present[isot] = true;
    if (psot == 0) break;
    p += psot;
  }
  return present;
}

void read_jpeg2000(const ByteFile& f, const NitfImage& im, int band, Raster& r) {
  const BlockMap map = read_block_map(f, im);
  FileSpan span{f.handle(), map.first, im.data_offset + im.data_length - map.first, 0};
  unsigned char sig[12] = {};
  f.read(map.first, sig, sizeof sig, "the JPEG 2000 codestream");
  const bool jp2 = sig[4] == 'j' && sig[5] == 'P' && sig[6] == ' ' && sig[7] == ' ';
  if (!jp2 && !(sig[0] == 0xFF && sig[1] == 0x4F))
    throw InputError(im.path, 0, "IC=" + im.ic + " but the image data is not a JPEG 2000 codestream (no SOC marker at byte " +
                                     std::to_string(map.first) + ")");
  OpjHandles h;
  std::string err;
  h.codec = opj_create_decompress(jp2 ? OPJ_CODEC_JP2 : OPJ_CODEC_J2K);
  opj_set_error_handler(h.codec, keep_first_message, &err);
  opj_set_warning_handler(h.codec, ignore_message, nullptr);
  opj_set_info_handler(h.codec, ignore_message, nullptr);
  opj_dparameters_t params;
  opj_set_default_decoder_parameters(&params);
  h.stream = make_stream(&span, true);
  auto fail = [&](const char* stage) {
    throw InputError(im.path, 0, std::string("JPEG 2000 ") + stage + ": " + (err.empty() ? "corrupt or truncated codestream" : err));
  };
  // strict (OpenJPEG 2.5's default, made explicit): a codestream that ends early is an error, where the
  // lenient mode decodes what it has
  if (!opj_setup_decoder(h.codec, &params) || !opj_decoder_set_strict_mode(h.codec, OPJ_TRUE) ||
      !opj_read_header(h.stream, h.codec, &h.image))
    fail("header");
  if (static_cast<int>(h.image->numcomps) != im.bands)
    throw InputError(im.path, 0, "the JPEG 2000 codestream has " + std::to_string(h.image->numcomps) + " components, NBANDS says " +
                                     std::to_string(im.bands));
  if (static_cast<long>(h.image->x1 - h.image->x0) != im.cols || static_cast<long>(h.image->y1 - h.image->y0) != im.rows)
    throw InputError(im.path, 0, "the JPEG 2000 codestream is " + std::to_string(h.image->x1 - h.image->x0) + " x " +
                                     std::to_string(h.image->y1 - h.image->y0) + ", the subheader says " + std::to_string(im.cols) +
                                     " x " + std::to_string(im.rows));
  const OPJ_INT32 gx = static_cast<OPJ_INT32>(h.image->x0), gy = static_cast<OPJ_INT32>(h.image->y0);
  {  // every tile the region meets must be in the codestream
    const uint64_t soc = codestream_start(f, im, span, jp2), first = first_tile_part(f, im, span, soc);
    const TileGrid g = codestream_tile_grid(f, im, span, soc);
    const std::vector<bool> present = codestream_tiles(f, im, span, first, g.across * g.down);
    const uint64_t c0 = (gx + r.x0 - g.x0) / g.width, c1 = (gx + r.x0 + r.width - 1 - g.x0) / g.width;
    const uint64_t r0 = (gy + r.y0 - g.y0) / g.height, r1 = (gy + r.y0 + r.height - 1 - g.y0) / g.height;
    for (uint64_t tr = r0; tr <= r1; ++tr)
      for (uint64_t tc = c0; tc <= c1; ++tc)
        if (!present[tr * g.across + tc])
          throw InputError(im.path, 0, "JPEG 2000: tile " + std::to_string(tr * g.across + tc) + " (of " +
                                           std::to_string(g.across * g.down) + ") is not in the codestream: a truncated or corrupt image");
  }
  if (!opj_set_decode_area(h.codec, h.image, gx + static_cast<OPJ_INT32>(r.x0), gy + static_cast<OPJ_INT32>(r.y0),
                           gx + static_cast<OPJ_INT32>(r.x0 + r.width), gy + static_cast<OPJ_INT32>(r.y0 + r.height)) ||
      !opj_decode(h.codec, h.stream, h.image) || !opj_end_decompress(h.codec, h.stream))
    fail("decoding");
  const opj_image_comp_t& c = h.image->comps[band];
  if (c.dx != 1 || c.dy != 1 || static_cast<long>(c.w) != r.width || static_cast<long>(c.h) != r.height || !c.data)
    throw InputError(im.path, 0, "JPEG 2000 component " + std::to_string(band + 1) + " is subsampled or not decoded to the region");
  for (size_t i = 0; i < r.data.size(); ++i) r.data[i] = static_cast<float>(c.data[i]);
}

// ---------------------------------------------------------------- writing

std::string field(const std::string& s, size_t n) {  // left-justified, blank-padded text field
  std::string o = s.substr(0, n);
  o.resize(n, ' ');
  return o;
}
std::string number_field(uint64_t v, size_t n, const char* name) {  // zero-padded decimal field
  std::string s = std::to_string(v);
  if (s.size() > n) throw InputError(std::string("NITF field ") + name + ": " + s + " does not fit in " + std::to_string(n) + " digits");
  return std::string(n - s.size(), '0') + s;
}

std::string utc_now() {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[16];
  std::strftime(b, sizeof b, "%Y%m%d%H%M%S", &tm);
  return b;
}

// CLEVEL by MIL-STD-2500C table A-10's limits on image size and file size.
std::string complexity_level(long w, long h, uint64_t file_bytes) {
  const long d = std::max(w, h);
  if (d <= 2048 && file_bytes < (uint64_t(50) << 20)) return "03";
  if (d <= 8192 && file_bytes < (uint64_t(1) << 30)) return "05";
  if (d <= 65536 && file_bytes < (uint64_t(2) << 30)) return "06";
  if (d <= 99999999 && file_bytes < uint64_t(10) * (uint64_t(1) << 30)) return "07";
  return "09";
}

}  // namespace

// ---------------------------------------------------------------- headers

bool is_nitf_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;  // a FIFO would block the open
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  char b[4] = {};
  const bool ok = std::fread(b, 1, 4, f) == 4 && (std::memcmp(b, "NITF", 4) == 0 || std::memcmp(b, "NSIF", 4) == 0);
  std::fclose(f);
  return ok;
}

NitfImage read_nitf_image(const std::string& path) {
  ByteFile f(path);
  NitfImage im;
  im.path = path;
  // file header: its fixed part up to HL, then the segment lengths
  const std::string fixed = f.read_string(0, 360, "the file header");
  FieldCursor fh(path, fixed, 0);
  im.version = fh.text(9, "FHDR/FVER");
  if (im.version != "NITF02.10" && im.version != "NSIF01.00")
    throw InputError(path, 0, "'" + FieldCursor::printable(im.version) + "': only NITF 2.1 (NITF02.10) and NSIF 1.0 are read");
  fh.skip(2 + 4 + 10 + 14 + 80 + kSecurityFields + 5 + 5 + 1 + 3 + 24 + 18, "CLEVEL .. OPHONE");
  fh.number(12, "FL");
  const uint64_t hl = fh.number(6, "HL");
  const std::string header = f.read_string(0, static_cast<size_t>(hl), "the file header (HL)");
  FieldCursor c(path, header, 0);
  c.skip(360, "FHDR .. HL");
  const uint64_t numi = c.number(3, "NUMI");
  if (numi == 0) throw InputError(path, 0, "no image segment (NUMI = 0)");
  im.image_segments = static_cast<int>(numi);
  const uint64_t lish = c.number(6, "LISH");
  const uint64_t li = c.number(10, "LI");
  // the first image subheader follows the file header
  const std::string sub = f.read_string(hl, static_cast<size_t>(lish), "the image subheader (LISH)");
  FieldCursor s(path, sub, hl);
  if (s.text(2, "IM") != "IM") throw InputError(path, 0, "byte " + std::to_string(hl) + ": no image subheader (IM) where HL points");
  s.skip(10 + 14 + 17 + 80 + kSecurityFields + 1 + 42, "IID1 .. ISORCE");
  im.rows = static_cast<long>(s.number(8, "NROWS"));
  im.cols = static_cast<long>(s.number(8, "NCOLS"));
  im.pvtype = s.trimmed(3, "PVTYPE");
  im.irep = s.trimmed(8, "IREP");
  s.skip(8, "ICAT");
  im.abpp = static_cast<int>(s.number(2, "ABPP"));
  im.pjust = s.text(1, "PJUST")[0];
  if (s.text(1, "ICORDS") != " ") s.skip(60, "IGEOLO");
  const uint64_t nicom = s.number(1, "NICOM");
  s.skip(static_cast<size_t>(80 * nicom), "ICOMn");
  im.ic = s.text(2, "IC");
  if (im.ic != "NC" && im.ic != "NM") s.skip(4, "COMRAT");
  uint64_t nbands = s.number(1, "NBANDS");
  if (nbands == 0) nbands = s.number(5, "XBANDS");
  im.bands = static_cast<int>(nbands);
  for (uint64_t b = 0; b < nbands; ++b) {
    s.skip(2 + 6 + 1 + 3, "IREPBANDn .. IMFLTn");
    const uint64_t nluts = s.number(1, "NLUTSn");
    if (nluts > 0) {
      const uint64_t nelut = s.number(5, "NELUTn");
      s.skip(static_cast<size_t>(nluts * nelut), "LUTDnm");
    }
  }
  s.skip(1, "ISYNC");
  im.imode = s.text(1, "IMODE")[0];
  im.nbpr = static_cast<long>(s.number(4, "NBPR"));
  im.nbpc = static_cast<long>(s.number(4, "NBPC"));
  im.nppbh = static_cast<long>(s.number(4, "NPPBH"));
  im.nppbv = static_cast<long>(s.number(4, "NPPBV"));
  im.nbpp = static_cast<int>(s.number(2, "NBPP"));
  s.skip(3 + 3 + 10 + 4, "IDLVL .. IMAG");
  for (const char* area : {"UDIDL", "IXSHDL"}) {
    const uint64_t len = s.number(5, area);
    if (len == 0) continue;
    if (len < 3) throw InputError(path, 0, std::string(area) + " = " + std::to_string(len) + " (at least 3 when not 0)");
    if (s.number(3, "UDOFL/IXSOFL") != 0) im.tre_overflow = true;
    const uint64_t at = s.file_offset();
    parse_tres(path, s.text(static_cast<size_t>(len - 3), area), at, im.tres);
  }
  im.data_offset = hl + lish;
  im.data_length = li;
  // the layout must describe the image
  if (im.rows <= 0 || im.cols <= 0 || im.bands <= 0) throw InputError(path, 0, "an empty image (NROWS, NCOLS or NBANDS is 0)");
  if (im.nppbh == 0 && im.nbpr == 1) im.nppbh = im.cols;  // "0000": one block across (images wider than 8192)
  if (im.nppbv == 0 && im.nbpc == 1) im.nppbv = im.rows;
  if (im.nbpr <= 0 || im.nbpc <= 0 || im.nppbh <= 0 || im.nppbv <= 0 || im.nbpr * im.nppbh < im.cols || im.nbpc * im.nppbv < im.rows)
    throw InputError(path, 0, "blocks (NBPR " + std::to_string(im.nbpr) + " x NPPBH " + std::to_string(im.nppbh) + ", NBPC " +
                                  std::to_string(im.nbpc) + " x NPPBV " + std::to_string(im.nppbv) + ") do not cover the image (" +
                                  std::to_string(im.cols) + " x " + std::to_string(im.rows) + ")");
  if (std::string("BPRS").find(im.imode) == std::string::npos)
    throw InputError(path, 0, std::string("IMODE '") + im.imode + "' is not B, P, R or S");
  if (im.pjust != 'R' && im.pjust != 'L') throw InputError(path, 0, std::string("PJUST '") + im.pjust + "' is not R or L");
  if (im.abpp <= 0 || im.abpp > im.nbpp) throw InputError(path, 0, "ABPP " + std::to_string(im.abpp) + " with NBPP " + std::to_string(im.nbpp));
  if (im.data_offset + im.data_length > f.size())
    throw InputError(path, 0, "truncated: the image data ends at byte " + std::to_string(im.data_offset + im.data_length) +
                                  ", the file has " + std::to_string(f.size()));
  return im;
}

const NitfTre* find_nitf_tre(const NitfImage& im, const std::string& tag) {
  for (const auto& t : im.tres)
    if (t.tag == tag) return &t;
  return nullptr;
}

ImageInfo nitf_image_info(const NitfImage& im) {
  check_readable(im);
  ImageInfo info;
  info.path = im.path;
  info.width = im.cols;
  info.height = im.rows;
  info.bands = im.bands;
  info.bits = im.abpp;
  info.rgb = (im.irep == "RGB" || im.irep == "RGB/LUT") && im.bands >= 3;
  if (im.pvtype == "R")
    info.format = im.nbpp == 32 ? "float" : "double";
  else
    info.format = std::string(im.pvtype == "SI" ? "int" : "uint") + std::to_string(im.nbpp);
  if (masked(im)) {
    ByteFile f(im.path);
    info.nodata = read_block_map(f, im).pad;
  }
  return info;
}

Raster read_nitf_region(const NitfImage& im, int band, long x0, long y0, long w, long h) {
  check_readable(im);
  if (band < 0 || band >= im.bands)
    throw InputError(im.path, 0, "band " + std::to_string(band + 1) + " does not exist (the image has " + std::to_string(im.bands) + ")");
  Raster r;
  r.x0 = std::max(0L, x0);
  r.y0 = std::max(0L, y0);
  r.width = std::max(0L, std::min(im.cols, x0 + w) - r.x0);
  r.height = std::max(0L, std::min(im.rows, y0 + h) - r.y0);
  if (r.width == 0 || r.height == 0) return r;
  r.data.resize(static_cast<size_t>(r.width) * r.height);
  ByteFile f(im.path);
  if (im.ic == "C8" || im.ic == "M8")
    read_jpeg2000(f, im, band, r);
  else
    read_uncompressed(f, im, band, r);
  return r;
}

// ---------------------------------------------------------------- NitfWriterU16

struct NitfWriterU16::Impl {
  std::string path, tmp;
  long width = 0, height = 0, next_row = 0;
  NitfWriteOptions opt;
  FILE* f = nullptr;
  bool closed = false;
  uint64_t fl_at = 0, li_at = 0, comrat_at = 0, data_at = 0;
  long nbpr = 1, nbpc = 1;
  long bw = 0, bh = 0;  // block (tile) width and height: opt.block, or the image's side when smaller
  int sample_bytes = 2;
  std::vector<uint16_t> strip;  // the block row being filled: opt.block rows x width
  long strip_rows = 0;
  // JPEG 2000
  FileSpan span{};
  OpjHandles opj;
  std::string opj_error;

  void put(const std::string& s) {
    if (std::fwrite(s.data(), 1, s.size(), f) != s.size()) throw InputError(path, 0, std::string("write error: ") + std::strerror(errno));
  }
  uint64_t here() const { return static_cast<uint64_t>(ftello(f)); }
  void patch(uint64_t at, const std::string& s) {
    if (fseeko(f, static_cast<off_t>(at), SEEK_SET) != 0) throw InputError(path, 0, "write error: cannot seek");
    put(s);
  }
  void write_headers();
  void start_jpeg2000();
  void flush_block_row();
};

void NitfWriterU16::Impl::write_headers() {
  const std::string date = utc_now();
  nbpr = (width + bw - 1) / bw;
  nbpc = (height + bh - 1) / bh;
  std::string tres;
  for (const auto& t : opt.tres) tres += field(t.tag, 6) + number_field(t.data.size(), 5, "CEL") + t.data;
  const bool j2k = opt.compression == NitfWriteOptions::Compression::j2k;
  // file header (one image segment, nothing else)
  put("NITF02.10");
  put("03");  // CLEVEL: patched at close
  put("BF01" + field("tpkit", 10) + date + field("", 80));
  put("U" + field("", kSecurityFields - 1));
  put("00000" "00000" "0");
  put(std::string(3, '\0'));  // FBKGC: black
  put(field("", 24) + field("", 18));
  fl_at = here();
  put(std::string(12, '0'));  // FL: patched
  const uint64_t hl = 404;
  put(number_field(hl, 6, "HL") + "001");
  std::string sub;
  sub += "IM" + field("tpkit", 10) + date + field("", 17) + field("", 80) + "U" + field("", kSecurityFields - 1) + "0" + field("", 42);
  sub += number_field(static_cast<uint64_t>(height), 8, "NROWS") + number_field(static_cast<uint64_t>(width), 8, "NCOLS");
  sub += "INT" + field("MONO", 8) + field("VIS", 8) + number_field(static_cast<uint64_t>(opt.abpp), 2, "ABPP") + "R";
  sub += " ";  // ICORDS: no corner coordinates (the RPC TRE georeferences the image)
  sub += "0";  // NICOM
  comrat_at = hl + sub.size() + 2;
  sub += j2k ? std::string("C8") + "N000" : std::string("NC");
  sub += "1" + field("M", 2) + field("", 6) + "N" + field("", 3) + "0";
  sub += "0B" + number_field(static_cast<uint64_t>(nbpr), 4, "NBPR") + number_field(static_cast<uint64_t>(nbpc), 4, "NBPC");
  sub += number_field(static_cast<uint64_t>(bw), 4, "NPPBH") + number_field(static_cast<uint64_t>(bh), 4, "NPPBV");
  sub += number_field(static_cast<uint64_t>(sample_bytes * 8), 2, "NBPP") + "001" "000" "0000000000" "1.0 ";
  sub += "00000";  // UDIDL
  sub += tres.empty() ? std::string("00000") : number_field(tres.size() + 3, 5, "IXSHDL") + "000" + tres;
  put(number_field(sub.size(), 6, "LISH"));
  li_at = here();
  put(std::string(10, '0'));  // LI: patched
  put("000" "000" "000" "000" "000" "00000" "00000");  // NUMS NUMX NUMT NUMDES NUMRES UDHDL XHDL
  if (here() != hl) throw std::logic_error("NitfWriterU16: file header length");
  put(sub);
  data_at = here();
}

void NitfWriterU16::Impl::start_jpeg2000() {
  opj.codec = opj_create_compress(OPJ_CODEC_J2K);
  opj_set_error_handler(opj.codec, keep_first_message, &opj_error);
  opj_set_warning_handler(opj.codec, ignore_message, nullptr);
  opj_set_info_handler(opj.codec, ignore_message, nullptr);
  opj_cparameters_t p;
  opj_set_default_encoder_parameters(&p);
  p.tcp_numlayers = 1;
  p.tcp_rates[0] = 0;  // lossless
  p.cp_disto_alloc = 1;
  p.irreversible = 0;  // reversible 5-3 wavelet
  p.tile_size_on = OPJ_TRUE;
  p.cp_tdx = static_cast<int>(bw);
  p.cp_tdy = static_cast<int>(bh);
  int levels = 1;
  while (levels < 6 && (std::min(bw, bh) >> levels) >= 16) ++levels;
  p.numresolution = levels;
  opj_image_cmptparm_t cp{};
  cp.dx = cp.dy = 1;
  cp.w = static_cast<OPJ_UINT32>(width);
  cp.h = static_cast<OPJ_UINT32>(height);
  cp.prec = static_cast<OPJ_UINT32>(opt.abpp);
  cp.sgnd = 0;
  opj.image = opj_image_tile_create(1, &cp, OPJ_CLRSPC_GRAY);
  opj.image->x0 = opj.image->y0 = 0;
  opj.image->x1 = static_cast<OPJ_UINT32>(width);
  opj.image->y1 = static_cast<OPJ_UINT32>(height);
  span = FileSpan{f, data_at, 0, 0};
  opj.stream = make_stream(&span, false);
  if (!opj_setup_encoder(opj.codec, &p, opj.image) || !opj_start_compress(opj.codec, opj.image, opj.stream))
    throw InputError(path, 0, "JPEG 2000 encoder: " + (opj_error.empty() ? std::string("cannot start") : opj_error));
}

NitfWriterU16::NitfWriterU16(const std::string& path, long width, long height, const NitfWriteOptions& options) : impl_(new Impl) {
  Impl& m = *impl_;
  m.path = path;
  m.width = width;
  m.height = height;
  m.opt = options;
  if (options.abpp < 1 || options.abpp > 16) throw InputError(path, 0, "NITF writer: " + std::to_string(options.abpp) + " bits per sample");
  if (options.block < 16 || options.block > 8192) throw InputError(path, 0, "NITF block of " + std::to_string(options.block) + " pixels (16 to 8192)");
  m.sample_bytes = options.abpp <= 8 ? 1 : 2;
  m.bw = std::min(options.block, width);
  m.bh = std::min(options.block, height);
  if (width <= 0 || height <= 0) throw InputError(path, 0, "NITF writer: an empty image");
  claim_output(path);
  m.tmp = claim_temp(path);
  m.f = std::fopen(m.tmp.c_str(), "w+b");
  if (!m.f) {
    discard_temp(m.tmp);
    throw InputError(path, 0, std::string("cannot open for writing: ") + std::strerror(errno));
  }
  try {
    m.write_headers();
    if (options.compression == NitfWriteOptions::Compression::j2k) m.start_jpeg2000();
  } catch (...) {
    m.opj.reset();
    std::fclose(m.f);
    m.f = nullptr;
    discard_temp(m.tmp);
    m.closed = true;
    throw;
  }
  m.strip.assign(static_cast<size_t>(m.bh) * width, 0);
}

NitfWriterU16::~NitfWriterU16() {
  impl_->opj.reset();  // before its file goes
  if (impl_->f) std::fclose(impl_->f);
  if (!impl_->closed) discard_temp(impl_->tmp);
}

// The filled block row (strip_rows rows of the image) as blocks (NC: big-endian, padded to full blocks
// with 0) or JPEG 2000 tiles (their real size at the edges).
void NitfWriterU16::Impl::flush_block_row() {
  const long row0 = next_row - strip_rows;
  const long tile_row = row0 / bh;
  std::vector<unsigned char> bytes;
  std::vector<uint16_t> tile;
  for (long bc = 0; bc < nbpr; ++bc) {
    const long x0 = bc * bw, tw = std::min(bw, width - x0);
    if (opt.compression == NitfWriteOptions::Compression::none) {
      bytes.assign(static_cast<size_t>(bw) * bh * sample_bytes, 0);
      for (long y = 0; y < strip_rows; ++y)
        for (long x = 0; x < tw; ++x) {
          const uint16_t v = strip[static_cast<size_t>(y) * width + x0 + x];
          unsigned char* p = bytes.data() + (static_cast<size_t>(y) * bw + x) * sample_bytes;
          if (sample_bytes == 1) {
            p[0] = static_cast<unsigned char>(v);
          } else {
            p[0] = static_cast<unsigned char>(v >> 8);
            p[1] = static_cast<unsigned char>(v & 0xFF);
          }
        }
      if (std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size())
        throw InputError(path, 0, std::string("write error: ") + std::strerror(errno));
    } else {
      const size_t n = static_cast<size_t>(tw) * strip_rows;
      bytes.resize(n * sample_bytes);
      for (long y = 0; y < strip_rows; ++y)
        for (long x = 0; x < tw; ++x) {
          const uint16_t v = strip[static_cast<size_t>(y) * width + x0 + x];
          if (sample_bytes == 1)
            bytes[static_cast<size_t>(y) * tw + x] = static_cast<unsigned char>(v);
          else
            std::memcpy(bytes.data() + (static_cast<size_t>(y) * tw + x) * 2, &v, 2);
        }
      if (!opj_write_tile(opj.codec, static_cast<OPJ_UINT32>(tile_row * nbpr + bc), bytes.data(), static_cast<OPJ_UINT32>(bytes.size()), opj.stream))
        throw InputError(path, 0, "JPEG 2000 encoder: " + (opj_error.empty() ? std::string("tile not written") : opj_error));
    }
  }
  strip_rows = 0;
}

void NitfWriterU16::write_rows(long y0, long rows, const uint16_t* data) {
  Impl& m = *impl_;
  if (y0 != m.next_row || y0 + rows > m.height) throw std::logic_error("NitfWriterU16: strips out of order");
  const uint16_t max = static_cast<uint16_t>((1u << m.opt.abpp) - 1);
  for (long r = 0; r < rows; ++r) {
    const uint16_t* src = data + static_cast<size_t>(r) * m.width;
    for (long x = 0; x < m.width; ++x)
      if (src[x] > max)
        throw InputError(m.path, 0, "sample " + std::to_string(src[x]) + " at (" + std::to_string(x) + ", " + std::to_string(y0 + r) +
                                        ") has more than " + std::to_string(m.opt.abpp) + " bits");
    std::copy(src, src + m.width, m.strip.begin() + static_cast<size_t>(m.strip_rows) * m.width);
    ++m.strip_rows;
    ++m.next_row;
    if (m.strip_rows == m.bh || m.next_row == m.height) m.flush_block_row();
  }
}

void NitfWriterU16::close() {
  Impl& m = *impl_;
  if (m.closed) return;
  if (m.next_row != m.height) throw std::logic_error("NitfWriterU16: image not complete");
  uint64_t end = m.here();
  if (m.opt.compression == NitfWriteOptions::Compression::j2k) {
    if (!opj_end_compress(m.opj.codec, m.opj.stream))
      throw InputError(m.path, 0, "JPEG 2000 encoder: " + (m.opj_error.empty() ? std::string("cannot finish") : m.opj_error));
    end = m.data_at + m.span.length;
    // COMRAT "Nxyz": numerically lossless at xy.z bits per pixel
    const double bpp = 8.0 * static_cast<double>(m.span.length) / (static_cast<double>(m.width) * m.height);
    m.patch(m.comrat_at, "N" + number_field(static_cast<uint64_t>(std::min(999.0, std::round(bpp * 10))), 3, "COMRAT"));
  }
  m.opj.reset();
  m.patch(m.li_at, number_field(end - m.data_at, 10, "LI"));
  m.patch(m.fl_at, number_field(end, 12, "FL"));
  m.patch(9, complexity_level(m.width, m.height, end));
  if (std::fflush(m.f) != 0 || std::fclose(m.f) != 0) {
    m.f = nullptr;
    throw InputError(m.path, 0, std::string("write error: ") + std::strerror(errno));
  }
  m.f = nullptr;
  m.closed = true;
  finish_output(m.tmp, m.path);
}

}  // namespace tpkit
