// The job list of a scaled-out tie-point run (tp-plan): overlapping pairs of a list of images, each
// pair split into regions of image 1, written for three engines that schedule it -- make -j, GNU
// parallel, Slurm job arrays -- with no scheduler of our own.
//
// Stages (every job is one shell command line; every path absolute and single-quoted, so names with
// spaces or quotes are safe; outputs under the work folder, which must be shared by all machines):
//   geometry  per pair:   tp-match --write-geometry WORK/geometry/pair-I-J.geometry IMG_I IMG_J
//   detect    per image and block (up to detect_regions regions of a row, detection_blocks): tp-match
//                         --geometry (a pair of the image) --detect N --region X0 Y0 W H --cache WORK/cache
//                         -o WORK/detect/image-I/block-K.detection IMG_I IMG_J
//                         (the detection tiles that start in the block, each detected once in all)
//   tiles     per region: tp-match --geometry ... --region X0 Y0 W H --cache WORK/cache
//                         -o WORK/tiles/pair-I-J/tile-K.matches IMG_I IMG_J (keypoints from the cache)
//   merge     per pair:   tp-merge -o WORK/pairs/pair-I-J.matches WORK/tiles/pair-I-J/tile-*.matches
//   chain     once:       tp-chain --images IMG... -o WORK/tracks.tracks WORK/pairs/*.matches
//                         (with the refine stage also --unrefined: tp-refine refines what the pairs could not)
//   refine    once, with the adjustment unless PlanOptions::refine is off:
//                         tp-refine -q IMG... --tracks WORK/tracks.tracks --threads T [REFINE OPTIONS]
//                         -o WORK/refined.tracks   (multi-image LSM: every view of a track against one
//                         template, and the views in the images each track lacks)
//   adjust    once:       rpc-adjust IMG... --tracks WORK/TRACKS --model M [--fixed IMG]...
//                         --threads T [ADJUST OPTIONS] -o WORK/adjusted   (target WORK/adjusted/rpc.bias)
//   ground    once:       tp-ground IMG... --tracks WORK/TRACKS --rpc IMG=WORK/adjusted/STEM_rpc.txt...
//                         --threads T [GROUND OPTIONS] -o WORK/ground.points
//                         (TRACKS: refined.tracks with the refine stage, else tracks.tracks)
//   ortho     once, with ortho_args (tp-plan --ortho-options): tp-ortho -q IMG... --rpc IMG=WORK/adjusted/STEM_rpc.txt...
//                         --threads T ORTHO OPTIONS -o WORK/orthos   (target WORK/orthos/STEM_1.ortho.tif: the
//                         orthos of every image through its adjusted model, on one grid)
// I, J, K count from 1 (I < J, in list order; regions row-major over image 1). IMG... of chain, adjust,
// ground and ortho: the images of the list that are in a pair, in list order; STEM: an image's file name
// without its extension, as rpc-adjust names the adjusted model it writes into -o.
//
// The adjustment (adjust and ground) needs an RPC model for every image of the chain, distinct stems
// (rpc-adjust's outputs are named by them) and no '=' in an image's path (tp-ground's --rpc IMAGE=FILE
// splits at the first one). PlanOptions::adjust decides what happens when one of these fails: automatic
// (the default: the plan ends with the chain, with a warning naming the reason), on (refused: an image
// without a model is InputError, the others UsageError), off (the plan ends with the chain, no warning).
// Every tp-match job gets --tile detect_tile: the memory of a job is bounded by one detection tile's
// SIFT pyramid (about 480 MB at tp-match's default of 1024 pixels, 340 MB at 768, 250 MB at 512).
//
// Pairs: two images are paired when their footprints overlap by min_overlap of the smaller one at least
// (the area of the intersection of their outlines at the models' middle height). A footprint is the
// image's ground outline (longitude, latitude in degrees) from its RPC model (image_footprint); an image
// without a model is paired with every image of the list, and an image paired with none is left out
// (warned). In a block of several dates, footprints two strips apart may meet along a sliver that
// tp-match cannot match (its coarse stage needs a real overlap): such pairs are left out and counted.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace tpkit {

struct Footprint {
  std::vector<std::array<double, 2>> lonlat;  // outline at both ends of the model's heights, degrees
  std::vector<std::array<double, 2>> middle;  // the border at the model's middle height (its height offset), in order
};

struct PlanImage {
  std::string path;  // absolute
  long width = 0, height = 0;
  std::optional<Footprint> footprint;
  bool rpc = false;  // a model was found for it (its tag 50844 or a sidecar: what rpc-adjust reads)
};

// The footprint of a width x height image from its RPC model (a sidecar or the TIFF tag, rpc_io.hpp):
// its border (16 points, corners included) localized at both ends of the model's height range. None
// without a model, or (warned) when the model does not localize the border. Throws InputError for an
// unreadable model.
std::optional<Footprint> image_footprint(const std::string& path, long width, long height);
// True when the footprints' longitude/latitude boxes meet, or when either is unknown. (Boxes do not
// wrap: footprints across the antimeridian are not handled.)
bool footprints_may_overlap(const PlanImage& a, const PlanImage& b);
// The area of the intersection of the footprints' middle outlines over the area of the smaller one
// (0..1; areas in a local equirectangular frame, metres enough for a ratio); 1 when either is unknown.
double footprint_overlap(const PlanImage& a, const PlanImage& b);

struct PlanOptions {
  long tile = 2048;                       // region size, image-1 pixels
  long overlap = 0;                       // regions grown by this on every side (duplicates merged)
  long detect_tile = 768;                 // tp-match --tile of every job (0: tp-match's default)
  long detect_regions = 4;                // regions of a row per detection job (detection_blocks)
  double min_overlap = 0.1;               // pairs overlapping less (footprint_overlap) are left out
  int threads = 1;                        // --threads of a tp-match, rpc-adjust, tp-ground job (and Slurm --cpus-per-task)
  std::string work;                       // shared work folder, absolute
  std::string bin;                        // folder of the tpkit tools; empty = found on PATH
  std::vector<std::string> match_args;    // more tp-match arguments, for every tp-match job
  // the adjustment stages (adjust, ground) after the chain; see the comment at the top
  enum class Adjust { automatic, on, off };
  Adjust adjust = Adjust::automatic;
  std::string adjust_model = "affine";    // rpc-adjust --model: shift, drift or affine (rpc-adjust's default)
  std::vector<std::string> fixed;         // rpc-adjust --fixed: absolute paths, each naming an image of the chain (image_index)
  std::vector<std::string> adjust_args;   // more rpc-adjust arguments (relative file names already made absolute)
  std::vector<std::string> ground_args;   // more tp-ground arguments (the same)
  std::vector<std::string> ortho_args;    // tp-ortho arguments (the same; --dem or --height among them): non-empty adds the ortho stage
  bool refine = true;                     // the refine stage (tp-refine) between the chain and the adjustment
  std::vector<std::string> refine_args;   // more tp-refine arguments
};

struct PlanJob {
  std::string target;                     // output, relative to the work folder
  std::vector<std::string> depends;       // targets it needs, relative to the work folder
  std::vector<size_t> detections;         // and the detection jobs of these images (0-based) it needs
  std::string command;                    // one shell command line
};

struct Plan {
  std::vector<std::array<size_t, 2>> pairs;  // 0-based image indices
  long pairs_below_overlap = 0;              // pairs whose footprints meet, by less than min_overlap
  std::vector<PlanJob> geometry, detect, tiles, merge, chain, refine, adjust, ground, ortho;  // refine, adjust, ground, ortho: empty without the adjustment
  std::vector<std::vector<std::string>> image_detections;  // per image: the targets of its detection jobs
};

struct PlanStage {
  std::string name;                  // geometry, detect, tiles, merge, chain, refine, adjust, ground, ortho
  const std::vector<PlanJob>* jobs;  // into the plan
};
// The stages of the plan that have jobs, in the order they run (refine, adjust and ground only with the adjustment).
std::vector<PlanStage> plan_stages(const Plan& p);
// The final target of the plan: ground.points with the adjustment, else tracks.tracks.
std::string plan_result(const Plan& p);

// More arguments of rpc-adjust (which = "rpc-adjust"), tp-ground (which = "tp-ground"), tp-refine (which =
// "tp-refine") or tp-ortho (which = "tp-ortho", whose --dem and --like name files; --compare and --tile are
// refused too) from the text of --adjust-options / --ground-options / --refine-options, split at white space: the options tp-plan sets itself are
// refused (UsageError naming option_name: -o, --tracks, --threads, --rpc (the models are those found
// beside the images, as for the footprints and tp-match), and for rpc-adjust --model and --fixed), and the
// file names made absolute (the jobs run in other folders): rpc-adjust's --dem, --gcp and --check,
// tp-ground's --compare, --align, --dz and --models.
std::vector<std::string> plan_tool_args(const std::string& text, const std::string& which, const std::string& option_name);

// Image sizes read from the files; throws InputError for an unreadable image, UsageError for fewer
// than two images or no overlapping pair.
std::vector<PlanImage> plan_images(const std::vector<std::string>& paths);

// The image list of --list: one path a line (spaces are part of it, a trailing '\r' and a UTF-8 byte
// order mark at the start of the file are not), blank lines and lines starting with '#' skipped. A regular file or a pipe; InputError for a folder, a
// device, binary content (a NUL byte) or a line longer than PATH_MAX (4096 bytes), found as the line
// is read (a device such as /dev/zero fails at once).
std::vector<std::string> read_image_list(const std::string& path);
// The plan's jobs. UsageError for bad options (tile sizes, an unknown --adjust-model, a --fixed image that
// is not in the chain), no overlapping pair, or (adjust = on) an adjustment that cannot be made: an image
// without a model is then InputError. See the comment at the top for the stages.
Plan make_plan(const std::vector<PlanImage>& images, const PlanOptions& o);

// The regions [x0, y0, w, h] of a width x height image: a grid of tile-sized cells (the last ones
// shorter) grown by overlap, clipped.
std::vector<std::array<long, 4>> plan_regions(long width, long height, long tile, long overlap);

// The blocks [x0, y0, w, h] of a width x height image that the detect stage gives one job each: the
// rows of the region grid (tile-sized cells, no overlap), each cut into runs of up to `regions` cells.
// A job costs a process's start and its memory's first touch (this VM: about 0.2 s), so fewer, longer
// jobs cost less in all: the 10000² tp-synth pair with regions of 2500 px and 768-px detection tiles,
// the jobs one after another on one thread, took 66.6 CPU s in 32 blocks of one region, 62.5 s in 16 of
// two, 59.9 s in 8 of four (a whole run's detection: 59.6 s), each job's peak 153, 174 and 204 MB.
std::vector<std::array<long, 4>> detection_blocks(long width, long height, long tile, long regions);

// 'text' for a POSIX shell ('\'' for a quote). Throws UsageError for a newline or NUL in it.
std::string shell_quote(const std::string& text);

// The engines' files, as text:
// Makefile fragment: targets relative to the work folder, `make -C WORK -f plan.mk -j N` ($ doubled).
// The detection targets of image I are listed once, in the variable detect-image-I, and a region job
// of pair I-J depends on $(detect-image-I) $(detect-image-J): the plan grows with pairs x regions, not
// with pairs x regions x images.
std::string plan_makefile(const Plan& p);
// A GNU parallel job file: one command a line (`parallel < FILE`).
std::string plan_job_file(const std::vector<PlanJob>& jobs);
// The Slurm array job: runs line $SLURM_ARRAY_TASK_ID of the job file named by its argument.
std::string plan_sbatch_script();
// Submits the stages (plan_stages) as job arrays, each after the previous (afterok); --wait waits for the last.
// The logs' --output pattern has the work folder's '%' doubled (Slurm expands %x, %j, ... in it) and the
// script refuses a work folder whose path holds a backslash (which turns the expansion of %a off: every
// job of a stage would write one log).
std::string plan_slurm_submit(const Plan& p, const PlanOptions& o);
// Runs the stages' job files with GNU parallel, stage after stage; arguments go to parallel.
std::string plan_parallel_runner(const Plan& p, const PlanOptions& o);

// Writes WORK/plan.mk, WORK/jobs/STAGE.jobs (every stage of plan_stages), WORK/slurm-array.sbatch,
// WORK/submit-slurm.sh, WORK/run-parallel.sh and the output folders (cache, geometry, detect/image-I,
// tiles/pair-I-J, pairs, logs), all in the run's output transaction.
// A work folder already used is taken only for the same plan (plan.mk the same: same images in the
// same order, same options), whose outputs it may then resume; the outputs of another plan would stand
// for other pairs, images or regions (make would call them up to date), so such a folder is refused
// (UsageError), as is one that holds outputs (geometry, detect, tiles, pairs, tracks.tracks, refined.tracks,
// adjusted, ground.points) but no plan.
void write_plan(const Plan& p, const PlanOptions& o);

}  // namespace tpkit
