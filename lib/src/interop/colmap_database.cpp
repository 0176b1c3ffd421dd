#include "tpkit/interop/colmap_database.hpp"

#include <sqlite3.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/text_table.hpp"

namespace fs = std::filesystem;

namespace tpkit {

namespace {

// COLMAP 3.8's schema, as `colmap database_creator` makes it (src/base/database.cc).
const char* const kSchema = R"sql(
CREATE TABLE IF NOT EXISTS cameras   (camera_id            INTEGER  PRIMARY KEY AUTOINCREMENT  NOT NULL,    model                INTEGER                             NOT NULL,    width                INTEGER                             NOT NULL,    height               INTEGER                             NOT NULL,    params               BLOB,    prior_focal_length   INTEGER                             NOT NULL);
CREATE TABLE IF NOT EXISTS images   (image_id   INTEGER  PRIMARY KEY AUTOINCREMENT  NOT NULL,    name       TEXT                                NOT NULL UNIQUE,    camera_id  INTEGER                             NOT NULL,    prior_qw   REAL,    prior_qx   REAL,    prior_qy   REAL,    prior_qz   REAL,    prior_tx   REAL,    prior_ty   REAL,    prior_tz   REAL,CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < 2147483647),FOREIGN KEY(camera_id) REFERENCES cameras(camera_id));
CREATE UNIQUE INDEX IF NOT EXISTS index_name ON images(name);
CREATE TABLE IF NOT EXISTS keypoints   (image_id  INTEGER  PRIMARY KEY  NOT NULL,    rows      INTEGER               NOT NULL,    cols      INTEGER               NOT NULL,    data      BLOB,FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS descriptors   (image_id  INTEGER  PRIMARY KEY  NOT NULL,    rows      INTEGER               NOT NULL,    cols      INTEGER               NOT NULL,    data      BLOB,FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS matches   (pair_id  INTEGER  PRIMARY KEY  NOT NULL,    rows     INTEGER               NOT NULL,    cols     INTEGER               NOT NULL,    data     BLOB);
CREATE TABLE IF NOT EXISTS two_view_geometries   (pair_id  INTEGER  PRIMARY KEY  NOT NULL,    rows     INTEGER               NOT NULL,    cols     INTEGER               NOT NULL,    data     BLOB,    config   INTEGER               NOT NULL,    F        BLOB,    E        BLOB,    H        BLOB,    qvec     BLOB,    tvec     BLOB);
CREATE TABLE IF NOT EXISTS tpkit_keypoint_ids   (image_id  INTEGER  PRIMARY KEY  NOT NULL,    rows      INTEGER               NOT NULL,    cols      INTEGER               NOT NULL,    data      BLOB);
)sql";

constexpr int kSimplePinhole = 0;
constexpr int kUncalibrated = 3;

class Db {
 public:
  Db(const std::string& path, int flags) : path_(path) {
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw InputError(path, 0, "cannot open as an SQLite database: " + why);
    }
  }
  ~Db() { sqlite3_close(db_); }
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;
  void exec(const char* sql) {
    char* err = nullptr;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
      const std::string why = err ? err : sqlite3_errmsg(db_);
      sqlite3_free(err);
      fail(why);
    }
  }
  [[noreturn]] void fail(const std::string& why) const { throw InputError(path_, 0, why); }
  sqlite3* get() const { return db_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

class Stmt {
 public:
  Stmt(Db& db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db.get(), sql, -1, &s_, nullptr) != SQLITE_OK) db.fail(sqlite3_errmsg(db.get()));
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;
  void bind(int i, long long v) { check(sqlite3_bind_int64(s_, i, v)); }
  void bind_null(int i) { check(sqlite3_bind_null(s_, i)); }
  void bind(int i, const std::string& v) { check(sqlite3_bind_text(s_, i, v.c_str(), -1, SQLITE_TRANSIENT)); }
  template <class T>
  void bind_blob(int i, const std::vector<T>& v) {
    check(sqlite3_bind_blob(s_, i, v.data(), static_cast<int>(v.size() * sizeof(T)), SQLITE_TRANSIENT));
  }
  // One step of an INSERT, then ready for the next.
  void run() {
    if (sqlite3_step(s_) != SQLITE_DONE) db_.fail(sqlite3_errmsg(db_.get()));
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  bool row() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc != SQLITE_DONE) db_.fail(sqlite3_errmsg(db_.get()));
    return false;
  }
  long long int64(int c) const { return sqlite3_column_int64(s_, c); }
  std::string text(int c) const {
    const unsigned char* t = sqlite3_column_text(s_, c);
    return t ? reinterpret_cast<const char*>(t) : "";
  }
  // A blob column as rows x cols values of T; InputError unless it holds exactly that many (rows and
  // cols come from the database: checked against the blob's size before they are multiplied, so that
  // no product overflows).
  template <class T>
  std::vector<T> blob(int c, long long rows, long long cols, const std::string& what) const {
    const long long bytes = sqlite3_column_bytes(s_, c);
    const long long have = bytes / static_cast<long long>(sizeof(T));
    if (rows < 0 || cols < 0) db_.fail(what + ": negative rows or cols (" + std::to_string(rows) + " x " + std::to_string(cols) + ")");
    if ((cols > 0 && rows > have / cols) || rows * cols * static_cast<long long>(sizeof(T)) != bytes)
      db_.fail(what + ": the blob holds " + std::to_string(bytes) + " bytes, rows x cols say " +
               (cols > 0 && rows > have / cols ? std::to_string(rows) + " x " + std::to_string(cols) + " values"
                                               : std::to_string(rows * cols * static_cast<long long>(sizeof(T)))));
    std::vector<T> v(static_cast<size_t>(rows * cols));
    if (bytes > 0) std::memcpy(v.data(), sqlite3_column_blob(s_, c), static_cast<size_t>(bytes));
    return v;
  }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) db_.fail(sqlite3_errmsg(db_.get()));
  }
  Db& db_;
  sqlite3_stmt* s_ = nullptr;
};

// ---- writing --------------------------------------------------------------------------------------

void insert_images(Db& db, const PeerKeypoints& k) {
  Stmt cam(db, "INSERT INTO cameras (camera_id, model, width, height, params, prior_focal_length) VALUES (?, ?, ?, ?, ?, 0)");
  Stmt img(db, "INSERT INTO images (image_id, name, camera_id) VALUES (?, ?, ?)");
  Stmt kp(db, "INSERT INTO keypoints (image_id, rows, cols, data) VALUES (?, ?, 2, ?)");
  Stmt ids(db, "INSERT INTO tpkit_keypoint_ids (image_id, rows, cols, data) VALUES (?, ?, 1, ?)");
  for (size_t i = 0; i < k.images.size(); ++i) {
    const PeerImage& im = k.images[i];
    const long long id = static_cast<long long>(i) + 1;
    if (im.ref.width <= 0 || im.ref.height <= 0)
      db.fail("COLMAP needs the size of image " + im.ref.path + ": the matches header gives none (name the image file with --images)");
    const double w = static_cast<double>(im.ref.width), h = static_cast<double>(im.ref.height);
    cam.bind(1, id);
    cam.bind(2, kSimplePinhole);
    cam.bind(3, im.ref.width);
    cam.bind(4, im.ref.height);
    cam.bind_blob(5, std::vector<double>{1.2 * std::max(w, h), w / 2, h / 2});
    cam.run();
    img.bind(1, id);
    img.bind(2, image_file_name(im.ref.path));
    img.bind(3, id);
    img.run();
    std::vector<float> xy;
    for (size_t e = 0; e < im.size(); ++e) {
      xy.push_back(static_cast<float>(im.x[e] + kColmapPixelOffset));
      xy.push_back(static_cast<float>(im.y[e] + kColmapPixelOffset));
    }
    kp.bind(1, id);
    kp.bind(2, static_cast<long long>(im.size()));
    kp.bind_blob(3, xy);
    kp.run();
    ids.bind(1, id);
    ids.bind(2, static_cast<long long>(im.size()));
    ids.bind_blob(3, std::vector<int64_t>(im.id.begin(), im.id.end()));
    ids.run();
  }
}

// COLMAP pixels of the pair's matches, the smaller image id first.
Eigen::MatrixX4d colmap_pair_points(const PeerKeypoints& k, const PeerPair& p, bool swap) {
  const PeerImage& a = k.images[swap ? p.image2 : p.image1];
  const PeerImage& b = k.images[swap ? p.image1 : p.image2];
  const auto& ia = swap ? p.idx2 : p.idx1;
  const auto& ib = swap ? p.idx1 : p.idx2;
  Eigen::MatrixX4d xy(static_cast<Eigen::Index>(ia.size()), 4);
  for (size_t r = 0; r < ia.size(); ++r)
    xy.row(static_cast<Eigen::Index>(r)) << static_cast<float>(a.x[ia[r]] + kColmapPixelOffset),
        static_cast<float>(a.y[ia[r]] + kColmapPixelOffset), static_cast<float>(b.x[ib[r]] + kColmapPixelOffset),
        static_cast<float>(b.y[ib[r]] + kColmapPixelOffset);
  return xy;
}

void insert_pairs(Db& db, const PeerKeypoints& k) {
  Stmt mt(db, "INSERT INTO matches (pair_id, rows, cols, data) VALUES (?, ?, 2, ?)");
  Stmt tv(db, "INSERT INTO two_view_geometries (pair_id, rows, cols, data, config, F) VALUES (?, ?, 2, ?, ?, ?)");
  for (const PeerPair& p : k.pairs) {  // one per pair (collect_peer_keypoints)
    const long long id1 = static_cast<long long>(p.image1) + 1, id2 = static_cast<long long>(p.image2) + 1;
    const bool swap = id1 > id2;
    const long long pair = colmap_pair_id(id1, id2);
    std::vector<uint32_t> data;
    for (size_t r = 0; r < p.idx1.size(); ++r) {
      data.push_back(swap ? p.idx2[r] : p.idx1[r]);
      data.push_back(swap ? p.idx1[r] : p.idx2[r]);
    }
    const long long rows = static_cast<long long>(p.idx1.size());
    mt.bind(1, pair);
    mt.bind(2, rows);
    mt.bind_blob(3, data);
    mt.run();
    if (rows < 8) continue;
    const Eigen::Matrix3d F = fundamental_8point(colmap_pair_points(k, p, swap));
    std::vector<double> f;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) f.push_back(F(i, j));  // row-major
    tv.bind(1, pair);
    tv.bind(2, rows);
    tv.bind_blob(3, data);
    tv.bind(4, kUncalibrated);
    tv.bind_blob(5, f);
    tv.run();
  }
}

// ---- reading --------------------------------------------------------------------------------------

bool has_table(Db& db, const std::string& table) {
  Stmt q(db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?");
  q.bind(1, table);
  return q.row();
}

struct ColmapImage {
  ImageRef ref;
  std::vector<float> xy;      // COLMAP pixels, 2 per keypoint
  std::vector<int64_t> ids;   // tpkit ids, or empty
  long long keypoints = 0;
};

std::map<long long, ColmapImage> read_images(Db& db) {
  std::map<long long, ColmapImage> images;
  Stmt q(db, "SELECT images.image_id, images.name, cameras.width, cameras.height FROM images "
             "LEFT JOIN cameras ON images.camera_id = cameras.camera_id");
  while (q.row()) images[q.int64(0)].ref = ImageRef{q.text(1), q.int64(2), q.int64(3)};
  Stmt kp(db, "SELECT image_id, rows, cols, data FROM keypoints");
  while (kp.row()) {
    const long long id = kp.int64(0), rows = kp.int64(1), cols = kp.int64(2);
    auto it = images.find(id);
    if (it == images.end()) db.fail("keypoints of image_id " + std::to_string(id) + ", which the images table lacks");
    if (cols != 2 && cols != 4 && cols != 6) db.fail("keypoints of image_id " + std::to_string(id) + " have " + std::to_string(cols) + " columns, not 2, 4 or 6");
    const std::vector<float> all = kp.blob<float>(3, rows, cols, "keypoints of image_id " + std::to_string(id));
    ColmapImage& im = it->second;
    im.keypoints = rows;
    for (long long r = 0; r < rows; ++r) {
      const float x = all[static_cast<size_t>(r * cols)], y = all[static_cast<size_t>(r * cols + 1)];
      if (!std::isfinite(x) || !std::isfinite(y))
        db.fail("keypoints of image_id " + std::to_string(id) + ": keypoint " + std::to_string(r) + " is not finite (" +
                format_number(x) + ", " + format_number(y) + ")");
      im.xy.push_back(x);
      im.xy.push_back(y);
    }
  }
  if (has_table(db, "tpkit_keypoint_ids")) {
    Stmt q2(db, "SELECT image_id, rows, data FROM tpkit_keypoint_ids");
    while (q2.row()) {
      auto it = images.find(q2.int64(0));
      if (it == images.end() || q2.int64(1) != it->second.keypoints)
        db.fail("table tpkit_keypoint_ids disagrees with the keypoints of image_id " + std::to_string(q2.int64(0)));
      it->second.ids = q2.blob<int64_t>(2, q2.int64(1), 1, "tpkit_keypoint_ids of image_id " + std::to_string(q2.int64(0)));
    }
  }
  return images;
}

Matches pair_matches(Db& db, std::map<long long, ColmapImage>& images, long long pair, long long rows, long long cols,
                     const std::vector<uint32_t>& data, const std::string& format) {
  const long long id2 = pair % kColmapMaxImageId, id1 = pair / kColmapMaxImageId;
  const std::string what = "pair_id " + std::to_string(pair);
  // COLMAP's pair_id puts the smaller image id first: (1, 2) and (2, 1) are one pair, one id
  if (id1 == id2) db.fail(what + " pairs image_id " + std::to_string(id1) + " with itself");
  if (id1 > id2 || id1 < 0)
    db.fail(what + " is not a COLMAP pair id: it decodes to image_id " + std::to_string(id1) + " then " +
            std::to_string(id2) + ", and pair_id = 2147483647 min(id1, id2) + max(id1, id2) puts the smaller first");
  auto a = images.find(id1), b = images.find(id2);
  if (a == images.end() || b == images.end()) db.fail(what + " names an image that the images table lacks");
  if (cols != 2) db.fail(what + ": matches have " + std::to_string(cols) + " columns, not 2");
  Matches m = peer_matches(a->second.ref, b->second.ref, format, db.path());
  // tpkit ids (tpkit_keypoint_ids): an id is one keypoint of its image. In image 1 of the tpkit file it
  // stood at one position (the keypoint's); only image 2's positions are refined per match, so one id
  // may stand at two positions there, each a refinement of the keypoint (tp-match moves it by at most
  // --max-shift, 1.5 px by default). A pair whose ids stand at two positions in both images, or at two
  // positions more than kRefinedApart apart in one, was not written from tpkit matches (all ids of an
  // image equal, say): its ids would join points that are not one.
  constexpr double kRefinedApart = 10;  // px
  struct Repeat {
    long long id = -1, record1 = -1, record2 = -1;
  };
  // the first id at two positions, and the first at two positions more than kRefinedApart apart
  auto repeats_of = [&](const ColmapImage& im, bool first) {
    std::pair<Repeat, Repeat> out;
    if (im.ids.empty()) return out;
    std::map<long long, std::pair<uint32_t, long long>> seen;  // tpkit id -> (keypoint index, record)
    for (long long r = 0; r < rows && out.second.id < 0; ++r) {
      const uint32_t k = data[static_cast<size_t>(2 * r + (first ? 0 : 1))];
      if (k >= im.keypoints) break;  // reported below
      const auto [it, fresh] = seen.emplace(im.ids[k], std::make_pair(k, r));
      const uint32_t j = it->second.first;
      const double dx = im.xy[2 * j] - im.xy[2 * k], dy = im.xy[2 * j + 1] - im.xy[2 * k + 1];
      if (fresh || (dx == 0 && dy == 0)) continue;
      const Repeat repeat{im.ids[k], it->second.second, r};
      if (out.first.id < 0) out.first = repeat;
      if (std::hypot(dx, dy) > kRefinedApart) out.second = repeat;
    }
    return out;
  };
  const auto [r1, far1] = repeats_of(a->second, true);
  const auto [r2, far2] = repeats_of(b->second, false);
  if (r1.id >= 0 && r2.id >= 0)
    db.fail(what + ": tpkit_keypoint_ids give one id to two positions in both images (id " + std::to_string(r1.id) +
            " of image_id " + std::to_string(id1) + " in matches " + std::to_string(r1.record1) + " and " +
            std::to_string(r1.record2) + ", id " + std::to_string(r2.id) + " of image_id " + std::to_string(id2) +
            " in matches " + std::to_string(r2.record1) + " and " + std::to_string(r2.record2) +
            "): not ids of tpkit matches");
  for (const auto& [far, image] : {std::make_pair(far1, id1), std::make_pair(far2, id2)})
    if (far.id >= 0)
      db.fail(what + ": tpkit_keypoint_ids give id " + std::to_string(far.id) + " of image_id " + std::to_string(image) +
              " two positions more than " + format_number(kRefinedApart) + " px apart (matches " + std::to_string(far.record1) +
              " and " + std::to_string(far.record2) + "): not one keypoint, refined");
  RecordList recs;
  for (long long r = 0; r < rows; ++r) {
    const uint32_t i = data[static_cast<size_t>(2 * r)], j = data[static_cast<size_t>(2 * r + 1)];
    if (i >= a->second.keypoints || j >= b->second.keypoints)
      db.fail(what + ": match " + std::to_string(r) + " names keypoint " + std::to_string(i >= a->second.keypoints ? i : j) +
              ", beyond the keypoints of its image");
    const ColmapImage &A = a->second, &B = b->second;
    recs.add(A.ids.empty() ? i : A.ids[i], A.xy[2 * i] - kColmapPixelOffset, A.xy[2 * i + 1] - kColmapPixelOffset,
             B.ids.empty() ? j : B.ids[j], B.xy[2 * j] - kColmapPixelOffset, B.xy[2 * j + 1] - kColmapPixelOffset);
  }
  recs.store(m);
  meta_set(m.meta, "colmap-pair-id", std::to_string(pair));
  meta_set(m.meta, "keypoints", std::to_string(a->second.keypoints) + " " + std::to_string(b->second.keypoints));
  return m;
}

}  // namespace

long long colmap_pair_id(long long image_id1, long long image_id2) {
  return kColmapMaxImageId * std::min(image_id1, image_id2) + std::max(image_id1, image_id2);
}

Eigen::Matrix3d fundamental_8point(const Eigen::MatrixX4d& xy) {
  const Eigen::Index n = xy.rows();
  if (n < 8) throw NumericalError("the 8-point method needs 8 correspondences, got " + std::to_string(n));
  // Hartley normalization of each image: centroid at 0, mean distance sqrt(2)
  auto normalizer = [&](int c) {
    const Eigen::Vector2d mean = xy.middleCols<2>(c).colwise().mean().transpose();
    const double d = (xy.middleCols<2>(c).rowwise() - mean.transpose()).rowwise().norm().mean();
    const double s = d > 0 ? std::sqrt(2.0) / d : 1.0;
    Eigen::Matrix3d T;
    T << s, 0, -s * mean.x(), 0, s, -s * mean.y(), 0, 0, 1;
    return T;
  };
  const Eigen::Matrix3d T1 = normalizer(0), T2 = normalizer(2);
  Eigen::MatrixXd A(n, 9);
  for (Eigen::Index r = 0; r < n; ++r) {
    const Eigen::Vector3d p = T1 * Eigen::Vector3d(xy(r, 0), xy(r, 1), 1), q = T2 * Eigen::Vector3d(xy(r, 2), xy(r, 3), 1);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) A(r, 3 * i + j) = q(i) * p(j);  // q^T F p, F row-major
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd f = svd.matrixV().col(8);
  Eigen::Matrix3d F;
  F << f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7), f(8);
  Eigen::JacobiSVD<Eigen::Matrix3d> r2(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d sv = r2.singularValues();
  sv(2) = 0;
  F = T2.transpose() * r2.matrixU() * sv.asDiagonal() * r2.matrixV().transpose() * T1;
  return F / F.norm();
}

void write_colmap_database(const std::string& path, const PeerKeypoints& k) {
  claim_output(path);
  const std::string tmp = claim_temp(path);
  try {
    {
      Db db(tmp, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
      db.exec(kSchema);
      db.exec("BEGIN TRANSACTION");
      insert_images(db, k);
      insert_pairs(db, k);
      db.exec("COMMIT");
    }
  } catch (const InputError& e) {
    discard_temp(tmp);
    throw InputError(path, 0, e.reason());
  } catch (...) {
    discard_temp(tmp);
    throw;
  }
  finish_output(tmp, path);
}

void write_colmap_text(const std::string& folder, const PeerKeypoints& k) {
  const std::string kdir = (fs::path(folder) / "keypoints").string();
  create_output_dir(kdir);
  const std::string zeros = [] {
    std::string z;
    for (int i = 0; i < 128; ++i) z += " 0";
    return z;
  }();
  for (const PeerImage& im : k.images) {
    AtomicOutput out((fs::path(kdir) / (image_file_name(im.ref.path) + ".txt")).string());
    out.stream() << im.size() << " 128\n";
    for (size_t e = 0; e < im.size(); ++e)
      out.stream() << format_number(static_cast<float>(im.x[e] + kColmapPixelOffset)) << ' '
                   << format_number(static_cast<float>(im.y[e] + kColmapPixelOffset)) << " 1 0" << zeros << '\n';
    out.commit();
  }
  AtomicOutput list((fs::path(folder) / "matches.txt").string());
  for (const PeerPair& p : k.pairs) {
    list.stream() << image_file_name(k.images[p.image1].ref.path) << ' ' << image_file_name(k.images[p.image2].ref.path) << '\n';
    for (size_t r = 0; r < p.idx1.size(); ++r) list.stream() << p.idx1[r] << ' ' << p.idx2[r] << '\n';
    list.stream() << '\n';
  }
  list.commit();
}

std::vector<Matches> read_colmap_database(const std::string& path, bool verified) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, 0, "no such database file");
  check_input_file(path, InputKind::regular);
  note_input(path);
  Db db(path, SQLITE_OPEN_READONLY);
  const std::string table = verified ? "two_view_geometries" : "matches";
  for (const std::string t : {"cameras", "images", "keypoints", table.c_str()})
    if (!has_table(db, t)) db.fail("not a COLMAP database: it has no table '" + t + "'");
  auto images = read_images(db);
  const std::string sql = "SELECT pair_id, rows, cols, data FROM " + table + (verified ? " WHERE config >= 2 AND rows > 0" : " WHERE rows > 0") +
                          " ORDER BY pair_id";
  Stmt q(db, sql.c_str());
  std::vector<Matches> out;
  while (q.row()) {
    const long long pair = q.int64(0), rows = q.int64(1), cols = q.int64(2);
    const auto data = q.blob<uint32_t>(3, rows, cols, table + " of pair_id " + std::to_string(pair));
    out.push_back(pair_matches(db, images, pair, rows, cols, data, verified ? "colmap" : "colmap-raw"));
  }
  return out;
}

}  // namespace tpkit
