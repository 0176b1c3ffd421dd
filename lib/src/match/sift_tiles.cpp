#include "tpkit/match/sift_tiles.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "tpkit/core/error.hpp"
#include "tpkit/core/huge_pages.hpp"
#include "tpkit/core/parallel_for.hpp"
#include "tpkit/core/text_table.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/match/opencv_memory.hpp"
#include "tpkit/match/root_sift.hpp"
#include "tpkit/match/sift_scale_space.hpp"

namespace tpkit {

std::string detector_tag(const SiftOptions& o, const ImageSource& src) {
  std::ostringstream s;
  // tpkit-N: the version of tpkit's SIFT, raised whenever its keypoints or descriptors change, so that a
  // keypoint cache of another version is not reused (2: every octave's descriptors sample every second pixel;
  // 3: an extremum's sub-pixel steps move it 6 octave pixels at most; 4: tpkit's own Gaussian blur, OpenCV's to rounding)
  s << "sift tpkit-4 " << src.rendering << " tile=" << o.tile << " overlap=" << o.overlap
    << " max_per_tile=" << o.max_per_tile << " contrast=" << format_number(o.contrast) << " edge=" << format_number(o.edge)
    << " sigma=" << format_number(o.sigma) << " layers=" << o.octave_layers << " descriptor=rootsift stretch=" << format_number(o.stretch_lo)
    << "," << format_number(o.stretch_hi) << " ids=tile-rank";
  if (src.nodata) s << " nodata=" << format_number(*src.nodata);
  if (!src.mask.empty()) s << " mask=" << src.mask;
  return s.str();
}

ScaleSpaceOptions scale_space_options(const SiftOptions& o) {
  ScaleSpaceOptions s;
  s.octave_layers = o.octave_layers;
  s.contrast = o.contrast;
  s.edge = o.edge;
  s.sigma = o.sigma;
  return s;
}

namespace {
// The order of keypoints within a tile (their rank: the id's low digits) and within a band of tiles.
bool keypoint_before(const cv::KeyPoint& p, const cv::KeyPoint& q) {
  if (p.pt.y != q.pt.y) return p.pt.y < q.pt.y;
  if (p.pt.x != q.pt.x) return p.pt.x < q.pt.x;
  if (p.size != q.size) return p.size < q.size;
  if (p.angle != q.angle) return p.angle < q.angle;
  if (p.response != q.response) return p.response < q.response;
  return p.octave < q.octave;
}

// The keypoints of tile t's core, in the image's pixels and their rank order, with their ids and RootSIFT
// descriptors (converted side by side on OpenCV's pool, straight into their ranked rows: on one thread
// the conversion took 1.75% of a 10000² image's detection, while the other thread waited).
Keypoints detect_tile(const ImageSource& src, const Raster& band, const SiftOptions& o, const Stretch& st, const Tile& t) {
  const int width = static_cast<int>(t.rx1 - t.rx0), height = static_cast<int>(t.ry1 - t.ry0);
  std::vector<uint8_t> valid;
  std::vector<uint8_t> u8 = render_u8(band, t.rx0, t.ry0, width, height, st, &valid);
  cv::Mat img(height, width, CV_8U, u8.data());
  cv::Mat mask(height, width, CV_8U, valid.data());
  // keypoints next to invalid pixels describe the nodata border: keep a margin of valid pixels
  cv::Mat eroded;
  bool any_invalid = std::find(valid.begin(), valid.end(), 0) != valid.end();
  if (any_invalid) cv::erode(mask, eroded, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(9, 9)));
  std::vector<cv::KeyPoint> kp;
  cv::Mat desc;
  // the keypoints of the tile's core, in the crop's pixels; the overlap is read for the blurs only, its
  // keypoints belong to other tiles
  ScaleSpaceOptions so = scale_space_options(o);
  so.region = {t.cx0 - 0.5 - t.rx0, t.cy0 - 0.5 - t.ry0, t.cx1 - 0.5 - t.rx0, t.cy1 - 0.5 - t.ry0};
  detect_sift_scale_space(img, any_invalid ? eroded : cv::Mat(), so, kp, desc);
  // a keypoint whose support reaches past the read region could differ between tilings
  std::vector<int> row;  // the descriptor rows of the keypoints kept
  for (int i = 0; i < static_cast<int>(kp.size()); ++i) {
    double x = kp[i].pt.x + t.rx0, y = kp[i].pt.y + t.ry0;
    double reach = 2.0 * kp[i].size;
    bool inner_x = (t.rx0 == 0 || x - reach >= t.rx0) && (t.rx1 == src.info.width || x + reach <= t.rx1);
    bool inner_y = (t.ry0 == 0 || y - reach >= t.ry0) && (t.ry1 == src.info.height || y + reach <= t.ry1);
    if (!inner_x || !inner_y) continue;
    row.push_back(i);
  }
  keep_strongest(kp, row, o.max_per_tile);
  std::vector<cv::KeyPoint> kept;  // kept[j]: keypoint row[j], in the image's pixels
  kept.reserve(row.size());
  for (int i : row) {
    cv::KeyPoint k = kp[i];
    k.pt.x += static_cast<float>(t.rx0);
    k.pt.y += static_cast<float>(t.ry0);
    k.class_id = t.index;
    kept.push_back(k);
  }
  std::vector<int> order(kept.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return keypoint_before(kept[a], kept[b]); });
  if (static_cast<long long>(order.size()) >= kIdsPerTile)
    throw InputError(src.path, 0, "detection tile " + std::to_string(t.index) + " holds more than " + std::to_string(kIdsPerTile) + " keypoints");
  Keypoints K;
  const int n = static_cast<int>(order.size());
  K.kp.resize(order.size());
  K.id.resize(order.size());
  K.desc.create(n, 128, CV_8U);
  cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& R) {
    for (int j = R.start; j < R.end; ++j) {
      K.kp[j] = kept[order[j]];
      root_sift_row(desc, row[order[j]], K.desc.ptr<uint8_t>(j));
      K.id[j] = static_cast<long long>(t.index) * kIdsPerTile + j;
    }
  });
  return K;
}
}  // namespace

int concurrent_sift_calls(int threads) { return std::max(1, threads / 2); }

std::vector<Tile> tiles_meeting(const std::vector<Tile>& grid, double x0, double y0, double x1, double y1) {
  std::vector<Tile> out;
  for (const Tile& t : grid)
    if (t.cx1 - 0.5 > x0 && t.cx0 - 0.5 < x1 && t.cy1 - 0.5 > y0 && t.cy0 - 0.5 < y1) out.push_back(t);
  return out;
}

std::vector<Tile> tiles_starting_in(const std::vector<Tile>& grid, long x0, long y0, long w, long h) {
  std::vector<Tile> out;
  for (const Tile& t : grid)
    if (t.cx0 >= x0 && t.cx0 < x0 + w && t.cy0 >= y0 && t.cy0 < y0 + h) out.push_back(t);
  return out;
}

Keypoints detect_sift_tiles(const ImageSource& src, const SiftOptions& o, int threads, Progress* progress) {
  const Stretch st = percentile_stretch(src, o.stretch_lo, o.stretch_hi, kStretchSamples, threads);
  return detect_sift_tile_set(src, o, st, tile_grid(src.info.width, src.info.height, o.tile, o.overlap), threads, progress);
}

namespace {
// The tiles [first, end) of one row of the grid and the band of the image they read (with the overlaps).
struct TileRow {
  size_t first, end;
  long x0, y0, x1, y1;
};

std::vector<TileRow> tile_rows(const std::vector<Tile>& tiles) {
  std::vector<TileRow> rows;
  for (size_t r0 = 0; r0 < tiles.size();) {
    TileRow R{r0, r0, tiles[r0].rx0, tiles[r0].ry0, tiles[r0].rx1, tiles[r0].ry1};
    for (; R.end < tiles.size() && tiles[R.end].cy0 == tiles[r0].cy0; ++R.end) {
      const Tile& t = tiles[R.end];
      R.x0 = std::min(R.x0, t.rx0), R.y0 = std::min(R.y0, t.ry0), R.x1 = std::max(R.x1, t.rx1), R.y1 = std::max(R.y1, t.ry1);
    }
    rows.push_back(R);
    r0 = R.end;
  }
  return rows;
}
}  // namespace

std::vector<Keypoints> detect_tiles_ranked(const ImageSource& src, const SiftOptions& o, const Stretch& st,
                                           const std::vector<Tile>& tiles, int threads, Progress* progress) {
  std::vector<Keypoints> res(tiles.size());
  threads = std::max(1, threads);
  // Tile rows one at a time: the row's band of the image (the columns its tiles read, with the overlaps)
  // is read once and the row's tiles are cut from it, so that a file stored in strips is decoded once per
  // row, not once per tile (a 10000-pixel-wide strip image would otherwise be decoded ten times over).
  // The next row's band is read on a thread of its own while this row's tiles are detected: decoding
  // is serial (1.2 s of a 10000² deflate image's 23 s of detection on 2 threads), and it costs one more
  // band in memory (10000 x 1216 floats, 49 MB). As the refinement reads its next bands (match_pair).
  // A band is read into the memory of the band before it (`spare`, done with): in fresh memory, each
  // page cost a fault and two zeroings (the 10000² pair's whole run: 576 thousand faults -> 385, 6.6 ->
  // 5.3 s of system time). Both buffers are reserved at the largest band's size (a reservation touches
  // no page), so that no band outgrows the memory it is given (the first row's band lacks the overlap
  // above it), and advised for huge pages (a detection job of one row of tiles too): their first touch
  // took 48 thousand faults of the pair's run.
  const std::vector<TileRow> rows = tile_rows(tiles);
  auto read = [&](const TileRow& R, Raster reuse) {
    return read_valid_region(src, R.x0, R.y0, R.x1 - R.x0, R.y1 - R.y0, std::move(reuse));
  };
  size_t most = 0;
  for (const TileRow& R : rows) most = std::max(most, static_cast<size_t>(R.x1 - R.x0) * static_cast<size_t>(R.y1 - R.y0));
  auto reserved = [most] {
    Raster r;
    r.data.reserve(most);
    advise_huge_pages(r.data.data(), most * sizeof(float));
    return r;
  };
  std::future<Raster> next;
  Raster spare = rows.size() > 1 ? reserved() : Raster{};
  for (size_t i = 0; i < rows.size(); ++i) {
    Raster band = i == 0 ? read(rows[0], reserved()) : next.get();
    // on a thread of its own where there are threads to spare (or, where none can start, when needed)
    if (i + 1 < rows.size())
      next = std::async(threads > 1 ? std::launch::async | std::launch::deferred : std::launch::deferred, read, std::cref(rows[i + 1]),
                        std::move(spare));
    const size_t r0 = rows[i].first, r1 = rows[i].end;
    const int workers = std::min<int>(concurrent_sift_calls(threads), static_cast<int>(r1 - r0));
    // OpenCV parallelises inside each tile on its own pool, sized once per process (opencv_threads.hpp)
    parallel_for(r1 - r0, workers, [&](size_t k) {
      res[r0 + k] = detect_tile(src, band, o, st, tiles[r0 + k]);
      if (progress) progress->add(1);
    });
    spare = std::move(band);
  }
  return res;
}

Keypoints gather_tiles(std::vector<Keypoints> res, const std::vector<Tile>& tiles, const Stretch& st) {
  // With several tiles, the blocks that the allocator keeps for reuse (opencv_memory.hpp: the scale
  // space's, and each band's tile descriptors once copied) go back to the system as the gathering goes,
  // or the copy would stack on them (10000² pair: the run's peak 949 -> 917 MiB). A one-tile image (Marseille)
  // keeps its scale space for the next image, whose page faults would cost more than the memory saves.
  const bool many = tiles.size() > 1;
  if (many) release_large_blocks();
  // Gather into the stable order. Tile cores split the rows into bands, so sorting by y first never
  // mixes two bands: gather band by band and free each band's tiles once copied. The output is
  // allocated once at its final size; the allocator maps it lazily, so resident memory grows as the
  // tiles shrink and peaks near one copy of the keypoints, not two.
  Keypoints K;
  K.stretch = st;
  K.tiles = static_cast<long>(tiles.size());
  size_t total = 0;
  for (const auto& r : res) total += r.kp.size();
  K.kp.reserve(total);
  K.id.reserve(total);
  K.desc.create(static_cast<int>(total), 128, CV_8U);
  struct Ref {
    size_t tile;
    int row;
  };
  auto before = [&](const Ref& a, const Ref& b) {
    const cv::KeyPoint &p = res[a.tile].kp[a.row], &q = res[b.tile].kp[b.row];
    if (keypoint_before(p, q)) return true;
    if (keypoint_before(q, p)) return false;
    return res[a.tile].id[a.row] < res[b.tile].id[b.row];
  };
  size_t t0 = 0;
  std::vector<Ref> refs, heap;
  while (t0 < tiles.size()) {
    size_t t1 = t0;
    while (t1 < tiles.size() && tiles[t1].cy0 == tiles[t0].cy0) ++t1;
    // detect_tile gives each tile's keypoints in this order (its rank is the id's low digits): then the
    // band is a merge of its tiles, else a sort (with the copies below side by side, a 10000² pair's two
    // gatherings 0.87 -> 0.56 s)
    refs.clear();
    bool tiles_sorted = true;
    for (size_t t = t0; t < t1 && tiles_sorted; ++t)
      for (int r = 1; r < static_cast<int>(res[t].kp.size()) && tiles_sorted; ++r) tiles_sorted = before({t, r - 1}, {t, r});
    if (tiles_sorted) {
      heap.clear();
      for (size_t t = t0; t < t1; ++t)
        if (!res[t].kp.empty()) heap.push_back({t, 0});
      auto after = [&](const Ref& a, const Ref& b) { return before(b, a); };  // a min-heap
      std::make_heap(heap.begin(), heap.end(), after);
      while (!heap.empty()) {
        std::pop_heap(heap.begin(), heap.end(), after);
        Ref& r = heap.back();
        refs.push_back(r);
        if (++r.row < static_cast<int>(res[r.tile].kp.size())) std::push_heap(heap.begin(), heap.end(), after);
        else heap.pop_back();
      }
    } else {
      for (size_t t = t0; t < t1; ++t)
        for (int r = 0; r < static_cast<int>(res[t].kp.size()); ++r) refs.push_back({t, r});
      std::sort(refs.begin(), refs.end(), before);
    }
    // the copies side by side on OpenCV's pool
    const size_t base = K.kp.size();
    K.kp.resize(base + refs.size());
    K.id.resize(base + refs.size());
    cv::parallel_for_(cv::Range(0, static_cast<int>(refs.size())), [&](const cv::Range& R) {
      for (int k = R.start; k < R.end; ++k) {
        const Ref& r = refs[static_cast<size_t>(k)];
        const size_t i = base + static_cast<size_t>(k);
        K.kp[i] = res[r.tile].kp[r.row];
        std::memcpy(K.desc.ptr<uint8_t>(static_cast<int>(i)), res[r.tile].desc.ptr<uint8_t>(r.row), 128);
        K.id[i] = res[r.tile].id[r.row];
      }
    }, std::max(1.0, static_cast<double>(refs.size()) / 8192));
    for (size_t t = t0; t < t1; ++t) res[t] = Keypoints{};
    if (many) release_large_blocks();
    t0 = t1;
  }
  return K;
}

Keypoints detect_sift_tile_set(const ImageSource& src, const SiftOptions& o, const Stretch& st, const std::vector<Tile>& tiles,
                               int threads, Progress* progress) {
  return gather_tiles(detect_tiles_ranked(src, o, st, tiles, threads, progress), tiles, st);
}

}  // namespace tpkit
