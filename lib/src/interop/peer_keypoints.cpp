#include "tpkit/interop/peer_keypoints.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <tuple>

#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"

namespace tpkit {

namespace {

using EntryKey = std::tuple<long long, double, double>;

bool names_same_image(const std::string& path, const std::string& name) {
  return path == name || image_file_name(path) == image_file_name(name) || image_stem(path) == image_stem(name);
}

struct Builder {
  PeerKeypoints k;
  std::map<std::string, size_t> image_index;
  std::vector<std::map<EntryKey, uint32_t>> entries;
  std::vector<std::string> order;  // --images, bound to the first header image of the same name
  std::vector<bool> bound;

  explicit Builder(const std::vector<std::string>& images) : order(images), bound(images.size(), false) {
    for (const auto& path : images) add(ImageRef{path, 0, 0});
  }

  size_t add(const ImageRef& ref) {
    k.images.push_back(PeerImage{ref, {}, {}, {}});
    entries.emplace_back();
    return k.images.size() - 1;
  }

  size_t image(const ImageRef& ref) {
    auto it = image_index.find(ref.path);
    if (it != image_index.end()) return it->second;
    size_t slot = k.images.size();
    for (size_t i = 0; i < order.size() && slot == k.images.size(); ++i)
      if (!bound[i] && names_same_image(order[i], ref.path)) {
        bound[i] = true;
        slot = i;
        k.images[i].ref = ref;
      }
    if (slot == k.images.size()) slot = add(ref);
    image_index[ref.path] = slot;
    return slot;
  }

  void check_order_used() const {
    for (size_t i = 0; i < order.size(); ++i)
      if (!bound[i]) throw UsageError("--images names " + order[i] + ", which no matches file holds");
  }

  uint32_t entry(size_t im, long long id, double x, double y) {
    auto& e = entries[im];
    auto [it, added] = e.emplace(EntryKey{id, x, y}, static_cast<uint32_t>(k.images[im].size()));
    if (added) {
      PeerImage& p = k.images[im];
      p.id.push_back(id);
      p.x.push_back(x);
      p.y.push_back(y);
    }
    return it->second;
  }
};

}  // namespace

std::string image_file_name(const std::string& path) { return std::filesystem::path(path).filename().string(); }

std::string image_stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

void check_peer_pair(const Matches& m) {
  if (m.image1.path.empty() || m.image2.path.empty())
    throw InputError(m.source, 0, "the header names no image1 / image2 lines: a peer format needs the images");
  if (m.image1.path == m.image2.path) throw InputError(m.source, 0, "pairs image " + m.image1.path + " with itself");
}

PeerKeypoints collect_peer_keypoints(const std::vector<Matches>& files, const std::vector<std::string>& order) {
  Builder b(order);
  std::map<std::pair<size_t, size_t>, size_t> pair_file;  // (smaller, larger image index) -> its file
  for (size_t f = 0; f < files.size(); ++f) {
    const Matches& m = files[f];
    check_peer_pair(m);
    PeerPair p;
    p.image1 = b.image(m.image1);
    p.image2 = b.image(m.image2);
    p.file = f;
    const auto [it, fresh] = pair_file.emplace(std::minmax(p.image1, p.image2), f);
    if (!fresh)
      throw InputError(m.source, 0, "pairs " + m.image1.path + " and " + m.image2.path + ", as " + files[it->second].source +
                                        " does: COLMAP and OpenMVG hold one set of matches per pair (tp-merge joins the files of "
                                        "one pair)");
    for (size_t r = 0; r < m.size(); ++r) {
      p.idx1.push_back(b.entry(p.image1, m.id1[r], m.xy(r, 0), m.xy(r, 1)));
      p.idx2.push_back(b.entry(p.image2, m.id2[r], m.xy(r, 2), m.xy(r, 3)));
    }
    b.k.pairs.push_back(std::move(p));
  }
  b.check_order_used();
  return std::move(b.k);
}

void assign_position_ids(std::vector<Matches>& files) {
  std::map<std::string, std::map<std::pair<double, double>, long long>> ids;
  auto id_of = [&](const std::string& image, double x, double y) {
    auto& m = ids[image];
    return m.emplace(std::make_pair(x, y), static_cast<long long>(m.size())).first->second;
  };
  for (auto& m : files)
    for (size_t r = 0; r < m.size(); ++r) {
      m.id1[r] = id_of(m.image1.path, m.xy(r, 0), m.xy(r, 1));
      m.id2[r] = id_of(m.image2.path, m.xy(r, 2), m.xy(r, 3));
    }
}

namespace {
// The name as a message shows it: control characters as \n, \r, \t or \xHH.
std::string shown(const std::string& name) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned char c : name) {
    if (c == '\n') out += "\\n";
    else if (c == '\r') out += "\\r";
    else if (c == '\t') out += "\\t";
    else if (c < 0x20 || c == 0x7f) out += std::string("\\x") + hex[c >> 4] + hex[c & 15];
    else out += static_cast<char>(c);
  }
  return out;
}

// A name that reads back from "# imageN: NAME" as itself (the header reader trims the value).
void check_image_name(const std::string& name, const std::string& source) {
  if (name.empty()) throw InputError(source, 0, "names an image with an empty name");
  for (unsigned char c : name)
    if (c < 0x20 || c == 0x7f)
      throw InputError(source, 0, "the image name '" + shown(name) +
                                      "' holds a line break or another control character: it cannot go into a tpkit header");
  if (name.front() == ' ' || name.back() == ' ')
    throw InputError(source, 0, "the image name '" + name + "' begins or ends with a space: it cannot go into a tpkit header");
}
}  // namespace

Matches peer_matches(const ImageRef& image1, const ImageRef& image2, const std::string& format, const std::string& source) {
  check_image_name(image1.path, source);
  check_image_name(image2.path, source);
  if (image1.path == image2.path) throw InputError(source, 0, "pairs image " + image1.path + " with itself");
  Matches m;
  m.source = source;
  m.image1 = image1;
  m.image2 = image2;
  meta_set(m.meta, "source-format", format);
  meta_set(m.meta, "source", source);
  return m;
}

void RecordList::add(long long i1, double x1, double y1, long long i2, double x2, double y2) {
  id1.push_back(i1);
  id2.push_back(i2);
  xy.insert(xy.end(), {x1, y1, x2, y2});
}

void RecordList::store(Matches& m) const {
  m.id1 = id1;
  m.id2 = id2;
  m.xy = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>>(xy.data(), static_cast<Eigen::Index>(size()), 4);
}

void name_images(std::vector<Matches>& files, const std::vector<std::string>& images) {
  if (images.empty()) return;
  auto rename = [&](ImageRef& ref) {
    for (const auto& path : images)
      if (names_same_image(path, ref.path)) {
        ref.path = path;
        if (ref.width <= 0 || ref.height <= 0) {
          const ImageInfo info = image_info(path);
          ref.width = info.width;
          ref.height = info.height;
        }
        return;
      }
  };
  for (auto& m : files) {
    rename(m.image1);
    rename(m.image2);
  }
}

void size_images(PeerKeypoints& k, const std::vector<std::string>& images) {
  for (auto& im : k.images) {
    if (im.ref.width > 0 && im.ref.height > 0) continue;
    for (const auto& path : images)
      if (names_same_image(path, im.ref.path)) {
        const ImageInfo info = image_info(path);
        im.ref.width = info.width;
        im.ref.height = info.height;
        break;
      }
  }
}

}  // namespace tpkit
