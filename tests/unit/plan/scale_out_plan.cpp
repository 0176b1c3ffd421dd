// tp-plan's pieces: shell quoting, regions, pairs from footprints, the jobs and the Makefile text.
#include "tpkit/plan/scale_out_plan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "tpkit/core/error.hpp"
#include "tpkit/match/sift_tiles.hpp"

using namespace tpkit;

TEST(ScaleOutPlan, ShellQuote) {
  EXPECT_EQ(shell_quote("a b"), "'a b'");
  EXPECT_EQ(shell_quote("it's"), "'it'\\''s'");
  EXPECT_EQ(shell_quote("$x `y` \"z\""), "'$x `y` \"z\"'");
  EXPECT_THROW(shell_quote("a\nb"), UsageError);
}

TEST(ScaleOutPlan, RegionsCoverTheImage) {
  const auto r = plan_regions(1000, 600, 400, 0);
  ASSERT_EQ(r.size(), 6u);  // 3 x 2
  EXPECT_EQ(r[2], (std::array<long, 4>{800, 0, 200, 400}));
  EXPECT_EQ(r[5], (std::array<long, 4>{800, 400, 200, 200}));
  const auto o = plan_regions(1000, 600, 400, 16);
  EXPECT_EQ(o[4], (std::array<long, 4>{384, 384, 432, 216}));
}

TEST(ScaleOutPlan, PairsFromFootprints) {
  PlanImage a{"/a", 10, 10, std::nullopt}, b{"/b", 10, 10, Footprint{{{{0, 0}}, {{1, 1}}}, {}}},
      c{"/c", 10, 10, Footprint{{{{2, 2}}, {{3, 3}}}, {}}}, d{"/d", 10, 10, Footprint{{{{0.5, 0.5}}, {{2.5, 2.5}}}, {}}};
  EXPECT_TRUE(footprints_may_overlap(a, b));  // unknown footprint: paired
  EXPECT_FALSE(footprints_may_overlap(b, c));
  EXPECT_TRUE(footprints_may_overlap(b, d));
  PlanOptions o;
  o.work = "/w d";
  o.tile = 256;
  const Plan p = make_plan({b, c, d}, o);
  ASSERT_EQ(p.pairs.size(), 2u);  // (b, d), (c, d)
  EXPECT_EQ(p.pairs[0], (std::array<size_t, 2>{0, 2}));
  EXPECT_EQ(p.pairs[1], (std::array<size_t, 2>{1, 2}));
  EXPECT_EQ(p.geometry.size(), 2u);
  EXPECT_EQ(p.tiles.size(), 2u);
  EXPECT_EQ(p.tiles[1].command,
            "tp-match -q --threads 1 --tile 768 --geometry '/w d/geometry/pair-2-3.geometry' --region 0 0 10 10 --cache '/w d/cache' "
            "-o '/w d/tiles/pair-2-3/tile-1.matches' '/c' '/d'");
  // each image once, through its first pair's geometry (d is image 2 of pair (b, d))
  ASSERT_EQ(p.detect.size(), 3u);
  EXPECT_EQ(p.detect[2].command,
            "tp-match -q --threads 1 --tile 768 --geometry '/w d/geometry/pair-1-3.geometry' --detect 2 --region 0 0 10 10 "
            "--cache '/w d/cache' -o '/w d/detect/image-3/block-1.detection' '/b' '/d'");
  // a region job needs the geometry and the detections of its own two images only (the plan grows as
  // pairs x regions, not pairs x regions x images)
  EXPECT_EQ(p.tiles[1].depends, (std::vector<std::string>{"geometry/pair-2-3.geometry"}));
  EXPECT_EQ(p.tiles[1].detections, (std::vector<size_t>{1, 2}));
  EXPECT_EQ(p.image_detections[2], (std::vector<std::string>{"detect/image-3/block-1.detection"}));
  EXPECT_EQ(p.merge[0].depends, (std::vector<std::string>{"tiles/pair-1-3/tile-1.matches"}));
  EXPECT_EQ(p.chain[0].command,
            "tp-chain -q --images '/b' '/c' '/d' -o '/w d/tracks.tracks' '/w d/pairs/pair-1-3.matches' '/w d/pairs/pair-2-3.matches'");
}

TEST(ScaleOutPlan, MakefileDoublesDollars) {
  PlanImage a{"/x/$a", 300, 300, std::nullopt}, b{"/x/b", 300, 300, std::nullopt};
  PlanOptions o;
  o.work = "/w";
  const std::string mk = plan_makefile(make_plan({a, b}, o));
  EXPECT_NE(mk.find("'/x/$$a'"), std::string::npos);
  EXPECT_EQ(mk.find("'/x/$a'"), std::string::npos);
  EXPECT_NE(mk.find("detect/image-2/block-1.detection: geometry/pair-1-2.geometry\n\t"), std::string::npos);
  EXPECT_NE(mk.find("detect-image-1 := detect/image-1/block-1.detection\n"), std::string::npos);
  EXPECT_NE(mk.find("tiles/pair-1-2/tile-1.matches: geometry/pair-1-2.geometry $(detect-image-1) $(detect-image-2)\n\t"),
            std::string::npos);
  EXPECT_NE(mk.find("pairs/pair-1-2.matches: tiles/pair-1-2/tile-1.matches\n"), std::string::npos);
  EXPECT_THROW(make_plan({a}, o), UsageError);
  o.detect_regions = 0;
  EXPECT_THROW(make_plan({a, b}, o), UsageError);
}

// The detect stage: every detection tile of every image in exactly one job, and no job without one;
// a job's block is up to detect_regions regions of a row.
TEST(ScaleOutPlan, DetectionTilesOnce) {
  PlanImage a{"/a", 5000, 3000, std::nullopt}, b{"/b", 4000, 4100, std::nullopt};
  for (long detect_tile : {0L, 512L, 768L, 3000L}) {
    for (long detect_regions : {1L, 2L, 4L, 100L}) {
      PlanOptions o;
      o.work = "/w";
      o.tile = 1100;
      o.detect_tile = detect_tile;
      o.detect_regions = detect_regions;
      const Plan p = make_plan({a, b}, o);
      for (size_t i = 0; i < 2; ++i) {
        const PlanImage& im = i == 0 ? a : b;
        const auto grid = tile_grid(im.width, im.height, detect_tile > 0 ? detect_tile : SiftOptions{}.tile, 0);
        std::vector<int> seen(grid.size(), 0);
        long jobs = 0;
        for (const PlanJob& j : p.detect) {
          if (j.target.rfind("detect/image-" + std::to_string(i + 1) + "/", 0) != 0) continue;
          ++jobs;
          long x, y, w, h;
          const size_t at = j.command.find("--region ");
          ASSERT_NE(at, std::string::npos);
          ASSERT_EQ(std::sscanf(j.command.c_str() + at, "--region %ld %ld %ld %ld", &x, &y, &w, &h), 4);
          const auto t = tiles_starting_in(grid, x, y, w, h);
          EXPECT_FALSE(t.empty()) << j.command;
          EXPECT_EQ(y % o.tile, 0) << j.command;
          EXPECT_LE(h, o.tile) << j.command;
          EXPECT_LE(w, o.tile * detect_regions) << j.command;
          // a whole row of regions when it holds them all (the widest image has 5 a row)
          if (detect_regions >= 5) {
            EXPECT_TRUE(x == 0 && w == im.width) << j.command;
          }
          for (const Tile& k : t) ++seen[static_cast<size_t>(k.index)];
        }
        EXPECT_GT(jobs, 0);
        for (int s : seen) EXPECT_EQ(s, 1) << "detect tile " << detect_tile << ", regions " << detect_regions << ", image " << i + 1;
      }
    }
  }
}

// Issue 24: the plan ends in the adjustment. After the chain (with the unrefined matches), one tp-refine
// job on the chain's images and tracks (issue 52), one rpc-adjust job on the refined tracks, then one
// tp-ground job through the adjusted models rpc-adjust writes (NAME_rpc.txt), in every engine's files,
// in that order; without the refine stage the adjustment reads the chain's tracks.
namespace {
PlanImage with_model(const std::string& path, std::optional<Footprint> f = std::nullopt) {
  PlanImage im{path, 300, 300, std::move(f)};
  im.rpc = true;
  return im;
}
std::vector<std::string> stage_names(const Plan& p) {
  std::vector<std::string> out;
  for (const PlanStage& s : plan_stages(p)) out.push_back(s.name);
  return out;
}
}  // namespace

TEST(ScaleOutPlan, AdjustAndGroundJobs) {
  // c overlaps neither: left out of the chain and so of the adjustment
  const PlanImage a = with_model("/i/a.tif", Footprint{{{{0, 0}}, {{1, 1}}}, {}}), b = with_model("/i/b 2.tif", Footprint{{{{0.5, 0.5}}, {{2, 2}}}, {}}),
                  c = with_model("/j/a.tif", Footprint{{{{5, 5}}, {{6, 6}}}, {}});
  PlanOptions o;
  o.work = "/w d";
  o.threads = 3;
  o.adjust_model = "drift";
  o.fixed = {"/i/a.tif"};
  o.adjust_args = {"--dem", "/x/dem.tif"};
  o.ground_args = {"--crs", "utm"};
  o.refine_args = {"--highpass", "1"};
  const Plan p = make_plan({a, b, c}, o);
  EXPECT_EQ(stage_names(p), (std::vector<std::string>{"geometry", "detect", "tiles", "merge", "chain", "refine", "adjust", "ground"}));
  ASSERT_EQ(p.chain.size(), 1u);
  EXPECT_EQ(p.chain[0].command.rfind("tp-chain -q --rpc-check 1 --threads 3 --unrefined --images '/i/a.tif' '/i/b 2.tif' -o '/w d/tracks.tracks' ", 0), 0u)
      << p.chain[0].command;
  ASSERT_EQ(p.refine.size(), 1u);
  ASSERT_EQ(p.adjust.size(), 1u);
  ASSERT_EQ(p.ground.size(), 1u);
  EXPECT_EQ(p.refine[0].target, "refined.tracks");
  EXPECT_EQ(p.refine[0].depends, (std::vector<std::string>{"tracks.tracks"}));
  EXPECT_EQ(p.refine[0].command,
            "tp-refine -q '/i/a.tif' '/i/b 2.tif' --tracks '/w d/tracks.tracks' --threads 3 '--highpass' '1' -o '/w d/refined.tracks'");
  EXPECT_EQ(p.adjust[0].target, "adjusted/rpc.bias");
  EXPECT_EQ(p.adjust[0].depends, (std::vector<std::string>{"refined.tracks"}));
  EXPECT_EQ(p.adjust[0].command,
            "rpc-adjust '/i/a.tif' '/i/b 2.tif' --tracks '/w d/refined.tracks' --model drift --fixed '/i/a.tif' --threads 3 "
            "'--dem' '/x/dem.tif' -o '/w d/adjusted'");
  EXPECT_EQ(p.ground[0].target, "ground.points");
  EXPECT_EQ(p.ground[0].depends, (std::vector<std::string>{"adjusted/rpc.bias", "refined.tracks"}));
  EXPECT_EQ(p.ground[0].command,
            "tp-ground '/i/a.tif' '/i/b 2.tif' --tracks '/w d/refined.tracks' --rpc '/i/a.tif=/w d/adjusted/a_rpc.txt' "
            "--rpc '/i/b 2.tif=/w d/adjusted/b 2_rpc.txt' --threads 3 '--crs' 'utm' -o '/w d/ground.points'");
  EXPECT_EQ(plan_result(p), "ground.points");

  const std::string mk = plan_makefile(p);
  EXPECT_NE(mk.find("tpkit-all: ground.points\n"), std::string::npos);
  EXPECT_NE(mk.find("\nrefined.tracks: tracks.tracks\n\ttp-refine "), std::string::npos);
  EXPECT_NE(mk.find("\nadjusted/rpc.bias: refined.tracks\n\trpc-adjust "), std::string::npos);
  EXPECT_NE(mk.find("\nground.points: adjusted/rpc.bias refined.tracks\n\ttp-ground "), std::string::npos);
  EXPECT_EQ(plan_job_file(p.adjust), p.adjust[0].command + "\n");
  // Slurm: refine after chain, adjust after refine, ground after adjust (each submit takes the previous
  // job's id as its afterok dependency), --wait on the last
  const std::string sub = plan_slurm_submit(p, o);
  const size_t chain = sub.find("\nsubmit chain 1\n"), refine = sub.find("\nsubmit refine 1\n"), adjust = sub.find("\nsubmit adjust 1\n"),
               ground = sub.find("\nsubmit ground 1 \"${wait[@]}\"\n");
  ASSERT_NE(chain, std::string::npos) << sub;
  ASSERT_NE(refine, std::string::npos) << sub;
  ASSERT_NE(adjust, std::string::npos) << sub;
  ASSERT_NE(ground, std::string::npos) << sub;
  EXPECT_LT(chain, refine);
  EXPECT_LT(refine, adjust);
  EXPECT_LT(adjust, ground);
  EXPECT_NE(sub.find("--cpus-per-task=3 "), std::string::npos);
  EXPECT_NE(plan_parallel_runner(p, o).find("for s in geometry detect tiles merge chain refine adjust ground; do\n"), std::string::npos);

  // without the refine stage: the chain keeps refined matches only, the adjustment reads its tracks
  o.refine = false;
  o.refine_args.clear();
  const Plan q = make_plan({a, b, c}, o);
  EXPECT_EQ(stage_names(q), (std::vector<std::string>{"geometry", "detect", "tiles", "merge", "chain", "adjust", "ground"}));
  EXPECT_EQ(q.chain[0].command.find("--unrefined"), std::string::npos);
  EXPECT_EQ(q.adjust[0].depends, (std::vector<std::string>{"tracks.tracks"}));
  EXPECT_EQ(q.adjust[0].command,
            "rpc-adjust '/i/a.tif' '/i/b 2.tif' --tracks '/w d/tracks.tracks' --model drift --fixed '/i/a.tif' --threads 3 "
            "'--dem' '/x/dem.tif' -o '/w d/adjusted'");
  EXPECT_EQ(q.ground[0].depends, (std::vector<std::string>{"adjusted/rpc.bias", "tracks.tracks"}));
  EXPECT_NE(plan_parallel_runner(q, o).find("for s in geometry detect tiles merge chain adjust ground; do\n"), std::string::npos);
}

TEST(ScaleOutPlan, AdjustmentThatCannotBeMade) {
  PlanOptions o;
  o.work = "/w";
  const PlanImage a = with_model("/i/a.tif"), b = with_model("/i/b.tif"), none{"/i/c.tif", 300, 300, std::nullopt},
                  same_stem = with_model("/j/a.tiff"), eq = with_model("/i/x=1.tif");
  for (const auto& images : {std::vector<PlanImage>{a, b, none}, std::vector<PlanImage>{a, b, same_stem}, std::vector<PlanImage>{a, eq}}) {
    // by default: the plan ends with the chain (warned), in every engine
    o.adjust = PlanOptions::Adjust::automatic;
    const Plan p = make_plan(images, o);
    EXPECT_TRUE(p.adjust.empty());
    EXPECT_TRUE(p.ground.empty());
    EXPECT_EQ(stage_names(p), (std::vector<std::string>{"geometry", "detect", "tiles", "merge", "chain"}));
    EXPECT_NE(plan_makefile(p).find("tpkit-all: tracks.tracks\n"), std::string::npos);
    EXPECT_EQ(plan_makefile(p).find("rpc-adjust"), std::string::npos);
    EXPECT_NE(plan_slurm_submit(p, o).find("\nsubmit chain 1 \"${wait[@]}\"\n"), std::string::npos);
    EXPECT_NE(plan_parallel_runner(p, o).find("for s in geometry detect tiles merge chain; do\n"), std::string::npos);
    // asked for: refused
    o.adjust = PlanOptions::Adjust::on;
    if (std::any_of(images.begin(), images.end(), [](const PlanImage& im) { return !im.rpc; }))
      EXPECT_THROW(make_plan(images, o), InputError);
    else
      EXPECT_THROW(make_plan(images, o), UsageError);
  }
  // off: no adjustment, also where it could be made
  o.adjust = PlanOptions::Adjust::off;
  EXPECT_TRUE(make_plan({a, b}, o).adjust.empty());
  o.adjust = PlanOptions::Adjust::automatic;
  EXPECT_EQ(make_plan({a, b}, o).adjust.size(), 1u);
  // bad options of the adjustment
  o.adjust_model = "projective";
  EXPECT_THROW(make_plan({a, b}, o), UsageError);
  o.adjust_model = "shift";
  o.fixed = {"/i/z.tif"};
  EXPECT_THROW(make_plan({a, b}, o), UsageError);
  const PlanImage far = with_model("/i/far.tif", Footprint{{{{5, 5}}, {{6, 6}}}, {}}), a1 = with_model("/i/a.tif", Footprint{{{{0, 0}}, {{1, 1}}}, {}}),
                  b1 = with_model("/i/b.tif", Footprint{{{{0, 0}}, {{1, 1}}}, {}});
  o.fixed = {"/i/far.tif"};  // left out of the plan: not in the chain
  EXPECT_THROW(make_plan({a1, b1, far}, o), UsageError);
  o.fixed = {"/i/b.tif"};
  const Plan p = make_plan({a1, b1, far}, o);
  ASSERT_EQ(p.adjust.size(), 1u);
  EXPECT_EQ(p.adjust[0].command, "rpc-adjust '/i/a.tif' '/i/b.tif' --tracks '/w/refined.tracks' --model shift --fixed '/i/b.tif' --threads 1 -o '/w/adjusted'");
}

TEST(ScaleOutPlan, AdjustAndGroundOptions) {
  EXPECT_EQ(plan_tool_args("  --loss 0.5   --flag 2 ", "rpc-adjust", "--adjust-options"),
            (std::vector<std::string>{"--loss", "0.5", "--flag", "2"}));
  // file names made absolute (the jobs run elsewhere): --dem one, --check until the next option
  const std::string cwd = std::filesystem::current_path().string();
  EXPECT_EQ(plan_tool_args("--dem d/dem.tif --dem-sigma 2 --check a.tracks ./b.tracks --height-prior=-5+-3 --dem=e.tif", "rpc-adjust", "--adjust-options"),
            (std::vector<std::string>{"--dem", cwd + "/d/dem.tif", "--dem-sigma", "2", "--check", cwd + "/a.tracks", cwd + "/b.tracks",
                                      "--height-prior=-5+-3", "--dem=" + cwd + "/e.tif"}));
  EXPECT_EQ(plan_tool_args("--prior-shift -1", "rpc-adjust", "--adjust-options"),  // a negative number is a value
            (std::vector<std::string>{"--prior-shift", "-1"}));
  for (const char* refused : {"-o x", "-ox", "--out x", "--tracks t", "--threads 4", "--model shift", "--model=shift", "--fixed a.tif", "--rpc a=b"})
    EXPECT_THROW(plan_tool_args(refused, "rpc-adjust", "--adjust-options"), UsageError) << refused;
  EXPECT_EQ(plan_tool_args("--crs utm --model x", "tp-ground", "--ground-options"),  // tp-ground has no --model of tp-plan's
            (std::vector<std::string>{"--crs", "utm", "--model", "x"}));
  for (const char* refused : {"-o x", "--output=x", "--tracks t", "--threads 4", "--rpc a=b"})
    EXPECT_THROW(plan_tool_args(refused, "tp-ground", "--ground-options"), UsageError) << refused;
  // issue 50, item 11: every file option of the two tools, not --dem and --check only (stdout stays "-")
  EXPECT_EQ(plan_tool_args("--gcp g.gcp --gcp=h.gcp --dem-sigma 2", "rpc-adjust", "--adjust-options"),
            (std::vector<std::string>{"--gcp", cwd + "/g.gcp", "--gcp=" + cwd + "/h.gcp", "--dem-sigma", "2"}));
  EXPECT_EQ(plan_tool_args("--align ref.tif --dz dz.txt --models=m --crs utm", "tp-ground", "--ground-options"),
            (std::vector<std::string>{"--align", cwd + "/ref.tif", "--dz", cwd + "/dz.txt", "--models=" + cwd + "/m", "--crs", "utm"}));
  EXPECT_EQ(plan_tool_args("--compare d/ref.tif --dz -", "tp-ground", "--ground-options"),
            (std::vector<std::string>{"--compare", cwd + "/d/ref.tif", "--dz", "-"}));
  // tp-refine: its image option made absolute, the plan's own refused
  EXPECT_EQ(plan_tool_args("--highpass 1 --reference a.tif --model-sigma 0.1", "tp-refine", "--refine-options"),
            (std::vector<std::string>{"--highpass", "1", "--reference", cwd + "/a.tif", "--model-sigma", "0.1"}));
  for (const char* refused : {"-o x", "--tracks t", "--threads 4", "--rpc a=b"})
    EXPECT_THROW(plan_tool_args(refused, "tp-refine", "--refine-options"), UsageError) << refused;
  try {
    plan_tool_args("--fixed a.tif", "rpc-adjust", "--adjust-options");
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--adjust-options: --fixed is refused there: it is tp-plan's --fixed"), std::string::npos) << e.what();
  }
}

// Issue 24: a block's strips two orbits apart meet along slivers; the plan pairs only footprints that
// overlap by --min-overlap of the smaller one (outlines at the middle height, in either orientation).
TEST(ScaleOutPlan, PairsNeedTheirFootprintsToOverlap) {
  auto square = [](double x0, double y0, double side, bool clockwise) {
    Footprint f;
    f.lonlat = {{{x0, y0}}, {{x0 + side, y0 + side}}};
    std::vector<std::array<double, 2>> m = {{{x0, y0}}, {{x0 + side, y0}}, {{x0 + side, y0 + side}}, {{x0, y0 + side}}};
    if (clockwise) std::reverse(m.begin(), m.end());
    f.middle = m;
    return f;
  };
  // near the equator: longitude and latitude degrees of equal length
  PlanImage a{"/a", 10, 10, square(0, 0, 0.01, false)}, b{"/b", 10, 10, square(0.007, 0.005, 0.01, true)},
      c{"/c", 10, 10, square(0.0095, 0.0, 0.01, false)}, small{"/s", 10, 10, square(0.002, 0.002, 0.004, true)},
      unknown{"/u", 10, 10, std::nullopt};
  EXPECT_NEAR(footprint_overlap(a, b), 0.3 * 0.5, 1e-3);
  EXPECT_NEAR(footprint_overlap(b, a), 0.3 * 0.5, 1e-3);
  EXPECT_NEAR(footprint_overlap(a, c), 0.05, 1e-3);
  EXPECT_NEAR(footprint_overlap(a, small), 1.0, 1e-9);  // of the smaller one
  EXPECT_EQ(footprint_overlap(a, unknown), 1.0);
  PlanOptions o;
  o.work = "/w";
  const Plan p = make_plan({a, b, c}, o);
  ASSERT_EQ(p.pairs.size(), 2u);  // a-b 0.15, b-c 0.375; a-c 0.05, below 0.1
  EXPECT_EQ(p.pairs[0], (std::array<size_t, 2>{0, 1}));
  EXPECT_EQ(p.pairs[1], (std::array<size_t, 2>{1, 2}));
  EXPECT_EQ(p.pairs_below_overlap, 1);
  o.min_overlap = 0;
  EXPECT_EQ(make_plan({a, b, c}, o).pairs.size(), 3u);
  o.min_overlap = 1.5;
  EXPECT_THROW(make_plan({a, b, c}, o), UsageError);
}
