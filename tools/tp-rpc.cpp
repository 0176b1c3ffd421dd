// tp-rpc: single points through an image's RPC model, streamed (man/tp-rpc.1). Options -> library
// (rpc_io.hpp, rpc_points.hpp) -> stdout or a file.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/ground/reference_dem.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_crop.hpp"
#include "tpkit/rpc/rpc_ground.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_points.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::string action, model, input = "-", output = "-", dem, dem_datum;
  std::vector<long> window;
  int band = 1;
  std::string compression = "none", crs = "geographic";
  long block = 1024;
  bool quiet = false;
};
}  // namespace

int main(int argc, char** argv) {
  using namespace tpkit;
  return run_tool("tp-rpc", argc, argv, [&](CLI::App& app) -> std::function<int()> {
    auto o = std::make_shared<Opts>();
    app.add_option("ACTION", o->action, "project (lon lat h -> x y h) | localize (x y h -> lon lat h) | crop (a window and its model)")
        ->required()
        ->check(CLI::IsMember({"project", "localize", "crop"}));
    app.add_option("MODEL", o->model, "an image (its tag 50844, its NITF RPC00B TRE or sidecar model) or a model file (_rpc.txt, .RPB, DIMAP .XML, .geom, .aux.xml)")
        ->required();
    app.add_option("-i,--input", o->input, "points to transform; - for stdin (default)");
    app.add_option("-o,--output", o->output, "the transformed points; - for stdout (default)");
    app.add_option("--dem", o->dem, "localize onto this GeoTIFF DEM (any CRS; heights above --dem-datum, m): input x y");
    app.add_option("--dem-datum", o->dem_datum, "the DEM's heights: ellipsoid | egm96 | egm2008 | a PROJ vertical grid file (default: the DEM's vertical GeoTIFF keys, ellipsoid without them)");
    app.add_option("--crs", o->crs, "project / localize: ground coordinates lon lat h (geographic, default) | utm (easting northing h, m, the model centre's zone) | ecef (X Y Z, m)")
        ->check(CLI::IsMember({"geographic", "utm", "ecef"}));
    app.add_option("--window", o->window, "crop: X0 Y0 W H, pixels (the window's top-left pixel, its width and height; default the whole image)")->expected(4);
    app.add_option("--band", o->band, "crop: the band written (from 1; default 1)");
    app.add_option("--compression", o->compression, "crop to NITF (-o OUT.ntf): none (IC=NC, default) | j2k (lossless JPEG 2000, IC=C8)")
        ->check(CLI::IsMember({"none", "j2k"}));
    app.add_option("--block", o->block, "crop to NITF: block (JPEG 2000 tile) size, pixels, 16 to 8192 (default 1024)");
    app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
    return [o]() {
      if (!o->dem.empty() && o->action != "localize") throw UsageError("--dem goes with localize");
      if (!o->dem_datum.empty() && o->dem.empty()) throw UsageError("--dem-datum goes with --dem");
      if (o->action == "crop") {
        if (o->crs != "geographic") throw UsageError("--crs goes with project and localize");
        if (o->output == "-") throw UsageError("crop needs -o OUT.tif (a GeoTIFF) or -o OUT.ntf (a NITF image), not stdout");
        if (!is_nitf_name(o->output) && (o->compression != "none" || o->block != 1024))
          throw UsageError("--compression and --block go with a NITF output (-o OUT.ntf)");
        if (o->block < 16 || o->block > 8192) throw UsageError("--block " + std::to_string(o->block) + ": 16 to 8192 pixels");
        if (o->band < 1) throw UsageError("--band counts from 1");
        check_outputs({{"-o", o->output}}, {o->model});
        const RpcSource src = load_rpc_model(o->model);
        if (o->window.empty()) {  // the whole image: a conversion (to NITF, or a GeoTIFF with the model in its tag)
          const ImageInfo info = image_info(o->model);
          o->window = {0, 0, info.width, info.height};
        }
        CropFormat format;
        format.jpeg2000 = o->compression == "j2k";
        format.block = o->block;
        const double change =
            crop_image_with_rpc(o->model, o->band - 1, src.model, o->window[0], o->window[1], o->window[2], o->window[3], o->output, format);
        if (!o->quiet) {
          char moved[64] = "";
          if (is_nitf_name(o->output)) std::snprintf(moved, sizeof moved, "; RPC00B precision: %.2g px at most", change);
          summary("crop " + std::to_string(o->window[2]) + " x " + std::to_string(o->window[3]) + " at (" + std::to_string(o->window[0]) +
                  ", " + std::to_string(o->window[1]) + ") of " + o->model + " with its model (" + rpc_form_name(src.form) + ") -> " +
                  o->output + moved);
        }
        return 0;
      }
      if (!o->window.empty()) throw UsageError("--window goes with crop");
      if (o->compression != "none" || o->block != 1024) throw UsageError("--compression and --block go with crop");
      check_outputs({{"-o", o->output}}, {o->model, o->input, o->dem});
      const RpcSource src = load_rpc_model(o->model);
      std::unique_ptr<ReferenceDem> dem;
      if (!o->dem.empty()) dem = std::make_unique<ReferenceDem>(o->dem, ReferenceDemOptions{o->dem_datum});
      const RpcPointDirection dir = o->action == "project" ? RpcPointDirection::Project : RpcPointDirection::Localize;
      const GroundConverter crs(parse_ground_crs(o->crs), src.model.lon_off, src.model.lat_off);
      const GroundConverter* ground = o->crs == "geographic" ? nullptr : &crs;
      // streamed, line by line as the points come: to stdout directly (a bad line stops the stream there,
      // the lines before it written), to a file through an atomic output (a failed run leaves none)
      RpcPointStats st;
      std::unique_ptr<AtomicOutput> file;
      if (o->output != "-") file = std::make_unique<AtomicOutput>(o->output);
      std::ostream& out = file ? file->stream() : std::cout;
      if (o->input == "-") {
        transform_rpc_points(std::cin, "stdin", out, src.model, dir, dem.get(), &st, ground);
      } else {
        std::ifstream in = open_input_file(o->input);
        transform_rpc_points(in, o->input, out, src.model, dir, dem.get(), &st, ground);
      }
      if (file) file->commit();
      if (!o->quiet)
        summary(o->action + " through " + src.path + " (" + rpc_form_name(src.form) + ")" + (ground ? ", ground in " + crs.description() : std::string()) +
                ": " + std::to_string(st.points) +
                " points, " + std::to_string(st.comments) + " lines passed through" +
                (st.outside ? ", " + std::to_string(st.outside) + " outside the model's validity box" : "") +
                (st.unsolved ? ", " + std::to_string(st.unsolved) + " without a solution (nan)" : ""));
      if (st.unsolved)
        warn(std::to_string(st.unsolved) + " points have no solution and are written as nan; the first: " + st.first_unsolved);
      if (st.outside) warn(std::to_string(st.outside) + " points lie outside the model's validity box: the model is extrapolated there");
      return 0;
    };
  }, tpkit_man_page);
}
