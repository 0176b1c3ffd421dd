#include "tpkit/core/formats.hpp"

#include <Eigen/LU>

#include <cmath>
#include <sstream>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"

namespace tpkit {

int ExtraColumns::find(const std::string& name) const {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

namespace {

// Collects every column not in `own` as an extra column.
ExtraColumns extras_of(const TextTable& t, const std::vector<int>& own) {
  ExtraColumns e;
  std::vector<int> idx;
  for (size_t c = 0; c < t.columns.size(); ++c) {
    bool mine = false;
    for (int o : own) mine |= (o == static_cast<int>(c));
    if (!mine) {
      e.names.push_back(t.columns[c]);
      idx.push_back(static_cast<int>(c));
    }
  }
  e.values.resize(static_cast<Eigen::Index>(t.rows.size()), static_cast<Eigen::Index>(idx.size()));
  for (size_t r = 0; r < t.rows.size(); ++r)
    for (size_t k = 0; k < idx.size(); ++k) e.values(r, k) = t.rows[r][idx[k]];
  return e;
}

void check_id(const TextTable& t, size_t r, int c) {
  double v = t.rows[r][c];
  if (std::floor(v) != v || std::fabs(v) > 9e15)
    throw InputError(t.source, t.row_line[r], "field '" + t.columns[c] + "' is not an integer id");
}

std::vector<std::string> seq_columns(const std::string& first, int k) {
  std::vector<std::string> c;
  if (!first.empty()) c.push_back(first);
  for (int i = 1; i <= k; ++i) {
    c.push_back("x" + std::to_string(i));
    c.push_back("y" + std::to_string(i));
  }
  return c;
}

template <class F>
void save_with(const std::string& path, F&& write) {
  AtomicOutput out(path);
  write(out.stream());
  out.commit();
}

void write_extra_names(std::vector<std::string>& cols, const ExtraColumns& e) {
  for (const auto& n : e.names) cols.push_back(n);
}

void append_extra(std::vector<double>& rec, const ExtraColumns& e, Eigen::Index r) {
  for (Eigen::Index k = 0; k < static_cast<Eigen::Index>(e.names.size()); ++k) rec.push_back(e.values(r, k));
}

void require_rows(const TextTable& t, size_t expect, const std::string& what) {
  if (t.rows.size() != expect)
    throw InputError(t.source, t.rows.size() > expect ? t.row_line[expect] : 0,
                     "a " + t.kind + " file holds " + what + "; found " + std::to_string(t.rows.size()) + " records");
}

}  // namespace

// ---- read options -------------------------------------------------------------------------------

ReadOptions matches_read_options() {
  ReadOptions o;
  o.kind = "matches";
  o.default_columns = [](size_t n) -> std::vector<std::string> {
    if (n == 6 || n == 0) return {"id1", "x1", "y1", "id2", "x2", "y2"};
    if (n == 4) return {"x1", "y1", "x2", "y2"};  // ids are then the record index
    return {};
  };
  return o;
}

ReadOptions tracks_read_options() {
  ReadOptions o;
  o.kind = "tracks";
  o.max_version = 2;  // 2: views not seen are "nan nan"
  // x<k>, y<k> and sigma<k> may be "nan": the track is not seen in image k
  o.may_be_missing = [](const std::string& c) {
    if (c.empty()) return false;
    size_t p = c[0] == 'x' || c[0] == 'y' ? 1 : c.compare(0, 5, "sigma") == 0 ? 5 : std::string::npos;
    if (p == std::string::npos || p >= c.size()) return false;
    for (size_t i = p; i < c.size(); ++i)
      if (c[i] < '0' || c[i] > '9') return false;
    return true;
  };
  o.default_columns = [](size_t n) -> std::vector<std::string> {
    if (n == 0) return seq_columns("track", 3);
    if (n >= 4 && n % 2 == 0) return seq_columns("", static_cast<int>(n / 2));       // x1 y1 ... (ids = index)
    if (n >= 5 && n % 2 == 1) return seq_columns("track", static_cast<int>(n / 2));  // track x1 y1 ...
    return {};
  };
  return o;
}

ReadOptions points_read_options() {
  ReadOptions o;
  o.kind = "points";
  o.default_columns = [](size_t n) -> std::vector<std::string> {
    if (n == 2 || n == 0) return {"x", "y"};
    return {};
  };
  return o;
}

namespace {
ReadOptions matrix_options(const std::string& kind) {
  ReadOptions o;
  o.kind = kind;
  o.columnar = false;
  return o;
}
}  // namespace

ReadOptions trifocal_read_options() { return matrix_options("trifocal"); }
ReadOptions homography_read_options() { return matrix_options("homography"); }
ReadOptions cameras_read_options() { return matrix_options("cameras"); }

// ---- from tables --------------------------------------------------------------------------------

Matches matches_from_table(const TextTable& t) {
  Matches m;
  m.source = t.source;
  m.meta = t.meta;
  if (t.images.size() >= 1) m.image1 = t.images[0];
  if (t.images.size() >= 2) m.image2 = t.images[1];
  if (!t.kind.empty() && (t.find("track") >= 0 || t.find("x3") >= 0))
    throw InputError(t.source, 0, "a matches header over the columns of a tracks file (track, x3, ...): not a matches file");
  int cx1 = t.require("x1"), cy1 = t.require("y1"), cx2 = t.require("x2"), cy2 = t.require("y2");
  // ids from the record index only for headerless input (awk output); a file that says it is a matches
  // file carries its keypoint ids, or the ids would join unrelated points
  int ci1 = t.kind.empty() ? t.find("id1") : t.require("id1"), ci2 = t.kind.empty() ? t.find("id2") : t.require("id2");
  std::vector<int> own = {cx1, cy1, cx2, cy2, ci1, ci2};
  const size_t n = t.rows.size();
  m.xy.resize(n, 4);
  m.id1.resize(n);
  m.id2.resize(n);
  for (size_t r = 0; r < n; ++r) {
    const auto& row = t.rows[r];
    m.xy.row(r) << row[cx1], row[cy1], row[cx2], row[cy2];
    if (ci1 >= 0) check_id(t, r, ci1);
    if (ci2 >= 0) check_id(t, r, ci2);
    m.id1[r] = ci1 >= 0 ? static_cast<long long>(row[ci1]) : static_cast<long long>(r);
    m.id2[r] = ci2 >= 0 ? static_cast<long long>(row[ci2]) : static_cast<long long>(r);
  }
  m.extra = extras_of(t, own);
  m.line = t.row_line;
  return m;
}

Tracks tracks_from_table(const TextTable& t) {
  Tracks tr;
  tr.source = t.source;
  tr.meta = t.meta;
  tr.images = t.images;
  int k = 0;
  while (t.find("x" + std::to_string(k + 1)) >= 0) ++k;
  if (k < 2) throw InputError(t.source, 0, "a tracks file needs columns x1 y1 x2 y2 at least");
  if (!t.kind.empty() && (t.find("id1") >= 0 || t.find("id2") >= 0))
    throw InputError(t.source, 0, "a tracks header over the columns of a matches file (id1, id2): not a tracks file");
  std::vector<int> own;
  int cid = t.kind.empty() ? t.find("track") : t.require("track");
  own.push_back(cid);
  for (int v = 1; v <= k; ++v) {
    own.push_back(t.require("x" + std::to_string(v)));
    own.push_back(t.require("y" + std::to_string(v)));
  }
  if (!tr.images.empty() && static_cast<int>(tr.images.size()) != k)
    throw InputError(t.source, 0, "header names " + std::to_string(tr.images.size()) + " images but the columns hold " +
                                      std::to_string(k) + " views");
  const size_t n = t.rows.size();
  tr.xy.resize(n, 2 * k);
  tr.id.resize(n);
  for (size_t r = 0; r < n; ++r) {
    for (int c = 0; c < 2 * k; ++c) tr.xy(r, c) = t.rows[r][own[1 + c]];
    int seen = 0;
    for (int v = 0; v < k; ++v) {
      const bool nx = std::isnan(tr.xy(r, 2 * v)), ny = std::isnan(tr.xy(r, 2 * v + 1));
      if (nx != ny)
        throw InputError(t.source, t.row_line[r],
                         std::string("view ") + std::to_string(v + 1) + " has " + (nx ? "x" : "y") + std::to_string(v + 1) +
                             " nan and " + (nx ? "y" : "x") + std::to_string(v + 1) +
                             " a number: a view not seen is nan in both columns");
      seen += !nx;
    }
    if (seen < 2)
      throw InputError(t.source, t.row_line[r],
                       "track seen in " + std::to_string(seen) + " view" + (seen == 1 ? "" : "s") + ": a track needs two or more");
    if (cid >= 0) check_id(t, r, cid);
    tr.id[r] = cid >= 0 ? static_cast<long long>(t.rows[r][cid]) : static_cast<long long>(r);
  }
  tr.extra = extras_of(t, own);
  tr.line = t.row_line;
  return tr;
}

int Tracks::seen_views(size_t track) const {
  int n = 0;
  for (int v = 0; v < views(); ++v) n += seen(track, v);
  return n;
}

bool Tracks::complete() const { return !xy.hasNaN(); }

Tracks tracks_seen_in_all_views(const Tracks& t, size_t* left_out) {
  std::vector<Eigen::Index> keep;
  keep.reserve(t.size());
  for (size_t r = 0; r < t.size(); ++r)
    if (t.seen_views(r) == t.views()) keep.push_back(static_cast<Eigen::Index>(r));
  if (left_out) *left_out = t.size() - keep.size();
  Tracks o;
  o.source = t.source;
  o.images = t.images;
  o.meta = t.meta;
  o.extra.names = t.extra.names;
  o.xy.resize(static_cast<Eigen::Index>(keep.size()), t.xy.cols());
  o.extra.values.resize(static_cast<Eigen::Index>(keep.size()), t.extra.values.cols());
  for (size_t i = 0; i < keep.size(); ++i) {
    const Eigen::Index r = keep[i], j = static_cast<Eigen::Index>(i);
    o.xy.row(j) = t.xy.row(r);
    if (t.extra.values.cols() > 0) o.extra.values.row(j) = t.extra.values.row(r);
    if (!t.id.empty()) o.id.push_back(t.id[static_cast<size_t>(r)]);
    if (!t.line.empty()) o.line.push_back(t.line[static_cast<size_t>(r)]);
  }
  return o;
}

Tracks read_tracks_seen_in_all_views(const std::string& path, int views, size_t* left_out) {
  const Tracks t = read_tracks(path);
  if (t.views() != views)
    throw InputError(t.source, 0, "needs tracks with exactly " + (views == 3 ? std::string("three") : std::to_string(views)) +
                                      " views; found " + std::to_string(t.views()));
  if (t.complete()) {
    if (left_out) *left_out = 0;
    return t;
  }
  Tracks all = tracks_seen_in_all_views(t, left_out);
  if (all.size() == 0)
    throw InputError(t.source, 0, "none of its " + std::to_string(t.size()) + " tracks is seen in all " +
                                      (views == 3 ? std::string("three") : std::to_string(views)) + " views");
  return all;
}

Points points_from_table(const TextTable& t) {
  Points p;
  p.source = t.source;
  p.meta = t.meta;
  p.images = t.images;
  int cx = t.require("x"), cy = t.require("y");
  p.xy.resize(t.rows.size(), 2);
  for (size_t r = 0; r < t.rows.size(); ++r) p.xy.row(r) << t.rows[r][cx], t.rows[r][cy];
  p.extra = extras_of(t, {cx, cy});
  p.line = t.row_line;
  return p;
}

namespace {
void require_width(const TextTable& t, size_t w, const std::string& what) {
  for (size_t r = 0; r < t.rows.size(); ++r)
    if (t.rows[r].size() != w)
      throw InputError(t.source, t.row_line[r], "expected " + std::to_string(w) + " numbers (" + what + "), found " +
                                                    std::to_string(t.rows[r].size()));
}
}  // namespace

Trifocal trifocal_from_table(const TextTable& t) {
  Trifocal tf;
  tf.source = t.source;
  tf.meta = t.meta;
  tf.images = t.images;
  require_width(t, 9, "T_i row-major");
  require_rows(t, 3, "three records (T_1, T_2, T_3)");
  double norm = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        tf.T[i](j, k) = t.rows[i][3 * j + k];
        norm += tf.T[i](j, k) * tf.T[i](j, k);
      }
  if (!(norm > 0)) throw InputError(t.source, t.row_line[0], "the trifocal tensor is zero");
  return tf;
}

Homography homography_from_table(const TextTable& t) {
  Homography h;
  h.source = t.source;
  h.meta = t.meta;
  h.images = t.images;
  require_width(t, 3, "a row of H");
  require_rows(t, 3, "three records (the rows of H)");
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) h.H(i, j) = t.rows[i][j];
  if (std::fabs(h.H.determinant()) < 1e-300 * h.H.norm())
    throw InputError(t.source, t.row_line[0], "the homography is singular");
  return h;
}

Cameras cameras_from_table(const TextTable& t) {
  Cameras c;
  c.source = t.source;
  c.meta = t.meta;
  c.images = t.images;
  require_width(t, 4, "a row of a 3x4 camera");
  if (t.rows.empty() || t.rows.size() % 3 != 0)
    throw InputError(t.source, t.rows.empty() ? 0 : t.row_line.back(),
                     "a cameras file holds three records per view; found " + std::to_string(t.rows.size()));
  // "# view N" lines must precede each camera, in order
  size_t views = t.rows.size() / 3;
  std::vector<int> seen(views, 0);
  for (const auto& ic : t.interleaved_comments) {
    std::istringstream is(ic.second);
    std::string w;
    long n = 0;
    if (is >> w && w == "view" && is >> n) {
      if (ic.first % 3 != 0 || n != static_cast<long>(ic.first / 3 + 1) || ic.first / 3 >= views)
        throw InputError(t.source, 0, "'# view " + std::to_string(n) + "' is out of place");
      seen[ic.first / 3] = 1;
    }
  }
  for (size_t v = 0; v < views; ++v)
    if (!seen[v]) throw InputError(t.source, t.row_line[3 * v], "camera " + std::to_string(v + 1) + " has no '# view " + std::to_string(v + 1) + "' line");
  c.P.resize(views);
  for (size_t v = 0; v < views; ++v)
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 4; ++k) c.P[v](r, k) = t.rows[3 * v + r][k];
  return c;
}

// ---- readers ------------------------------------------------------------------------------------

Matches read_matches(const std::string& path) { return matches_from_table(read_table_file(path, matches_read_options())); }
Tracks read_tracks(const std::string& path) { return tracks_from_table(read_table_file(path, tracks_read_options())); }
Points read_points(const std::string& path) { return points_from_table(read_table_file(path, points_read_options())); }
Trifocal read_trifocal(const std::string& path) { return trifocal_from_table(read_table_file(path, trifocal_read_options())); }
Homography read_homography(const std::string& path) {
  return homography_from_table(read_table_file(path, homography_read_options()));
}
Cameras read_cameras(const std::string& path) { return cameras_from_table(read_table_file(path, cameras_read_options())); }

// ---- writers ------------------------------------------------------------------------------------

void write_matches(std::ostream& os, const Matches& m) {
  std::vector<std::string> cols = {"id1", "x1", "y1", "id2", "x2", "y2"};
  write_extra_names(cols, m.extra);
  write_header(os, "matches", 1, {m.image1, m.image2}, m.meta, cols);
  std::vector<double> rec;
  for (Eigen::Index r = 0; r < m.xy.rows(); ++r) {
    rec = {static_cast<double>(m.id1[r]), m.xy(r, 0), m.xy(r, 1), static_cast<double>(m.id2[r]), m.xy(r, 2), m.xy(r, 3)};
    append_extra(rec, m.extra, r);
    write_record(os, rec);
  }
}

void write_tracks(std::ostream& os, const Tracks& t) {
  int k = t.views();
  auto cols = seq_columns("track", k);
  write_extra_names(cols, t.extra);
  write_header(os, "tracks", t.complete() ? 1 : 2, t.images, t.meta, cols);
  std::vector<double> rec;
  for (Eigen::Index r = 0; r < t.xy.rows(); ++r) {
    rec.assign(1, static_cast<double>(t.id.empty() ? r : t.id[r]));
    for (int c = 0; c < 2 * k; ++c) rec.push_back(t.xy(r, c));
    append_extra(rec, t.extra, r);
    write_record(os, rec);
  }
}

void write_points(std::ostream& os, const Points& p) {
  std::vector<std::string> cols = {"x", "y"};
  write_extra_names(cols, p.extra);
  write_header(os, "points", 1, p.images, p.meta, cols);
  std::vector<double> rec;
  for (Eigen::Index r = 0; r < p.xy.rows(); ++r) {
    rec = {p.xy(r, 0), p.xy(r, 1)};
    append_extra(rec, p.extra, r);
    write_record(os, rec);
  }
}

std::array<Eigen::Matrix3d, 3> normalized_trifocal(const std::array<Eigen::Matrix3d, 3>& T) {
  double n2 = 0, big = 0;
  for (const auto& Ti : T) {
    n2 += Ti.squaredNorm();
    for (int j = 0; j < 9; ++j)
      if (std::fabs(Ti.data()[j]) > std::fabs(big)) big = Ti.data()[j];
  }
  if (!(n2 > 0) || !std::isfinite(n2)) throw NumericalError("the trifocal tensor is zero or not finite");
  double s = (big < 0 ? -1.0 : 1.0) / std::sqrt(n2);
  std::array<Eigen::Matrix3d, 3> out;
  for (int i = 0; i < 3; ++i) out[i] = T[i] * s;
  return out;
}

void write_trifocal(std::ostream& os, const Trifocal& t) {
  auto T = normalized_trifocal(t.T);
  write_header(os, "trifocal", 1, t.images, t.meta, {});
  os << "# record i = T_i (i = 1..3), entries T_i^{jk} row j, column k, row-major; x ~ (x, y, 1) in pixels\n";
  for (int i = 0; i < 3; ++i) {
    std::vector<double> rec;
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) rec.push_back(T[i](j, k));
    write_record(os, rec);
  }
}

void write_homography(std::ostream& os, const Homography& h) {
  if (!h.H.allFinite()) throw NumericalError("the homography is not finite");
  write_header(os, "homography", 1, h.images, h.meta, {});
  os << "# x2 ~ H x1 on homogeneous pixel coordinates (x, y, 1); one row of H per record\n";
  for (int i = 0; i < 3; ++i) write_record(os, {h.H(i, 0), h.H(i, 1), h.H(i, 2)});
}

void write_cameras(std::ostream& os, const Cameras& c) {
  write_header(os, "cameras", 1, c.images, c.meta, {});
  os << "# x ~ P X: one 3x4 projection matrix per view, one row per record\n";
  for (size_t v = 0; v < c.P.size(); ++v) {
    if (!c.P[v].allFinite()) throw NumericalError("camera " + std::to_string(v + 1) + " is not finite");
    os << "# view " << (v + 1) << '\n';
    for (int r = 0; r < 3; ++r) write_record(os, {c.P[v](r, 0), c.P[v](r, 1), c.P[v](r, 2), c.P[v](r, 3)});
  }
}

void save_matches(const std::string& path, const Matches& m) { save_with(path, [&](std::ostream& os) { write_matches(os, m); }); }
void save_tracks(const std::string& path, const Tracks& t) { save_with(path, [&](std::ostream& os) { write_tracks(os, t); }); }
void save_points(const std::string& path, const Points& p) { save_with(path, [&](std::ostream& os) { write_points(os, p); }); }
void save_trifocal(const std::string& path, const Trifocal& t) { save_with(path, [&](std::ostream& os) { write_trifocal(os, t); }); }
void save_homography(const std::string& path, const Homography& h) {
  save_with(path, [&](std::ostream& os) { write_homography(os, h); });
}
void save_cameras(const std::string& path, const Cameras& c) { save_with(path, [&](std::ostream& os) { write_cameras(os, c); }); }

}  // namespace tpkit
