// tp-rpc: single points through an image's RPC model, streamed (man/tp-rpc.1). Options -> library
// (rpc_io.hpp, rpc_points.hpp) -> stdout or a file.
#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_crop.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_points.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::string action, model, input = "-", output = "-", dem;
  std::vector<long> window;
  int band = 1;
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
    app.add_option("MODEL", o->model, "an image (its tag 50844 or sidecar model) or a model file (_rpc.txt, .RPB, DIMAP .XML)")
        ->required();
    app.add_option("-i,--input", o->input, "points to transform; - for stdin (default)");
    app.add_option("-o,--output", o->output, "the transformed points; - for stdout (default)");
    app.add_option("--dem", o->dem, "localize onto this GeoTIFF DEM (EPSG:4326, heights above the ellipsoid, m): input x y");
    app.add_option("--window", o->window, "crop: X0 Y0 W H, pixels (the window's top-left pixel, its width and height)")->expected(4);
    app.add_option("--band", o->band, "crop: the band written (from 1; default 1)");
    app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
    return [o]() {
      if (!o->dem.empty() && o->action != "localize") throw UsageError("--dem goes with localize");
      if (o->action == "crop") {
        if (o->window.size() != 4) throw UsageError("crop needs --window X0 Y0 W H");
        if (o->output == "-") throw UsageError("crop needs -o OUT.tif (a GeoTIFF, not stdout)");
        if (o->band < 1) throw UsageError("--band counts from 1");
        check_outputs({{"-o", o->output}}, {o->model});
        const RpcSource src = load_rpc_model(o->model);
        crop_image_with_rpc(o->model, o->band - 1, src.model, o->window[0], o->window[1], o->window[2], o->window[3], o->output);
        if (!o->quiet)
          summary("crop " + std::to_string(o->window[2]) + " x " + std::to_string(o->window[3]) + " at (" + std::to_string(o->window[0]) +
                  ", " + std::to_string(o->window[1]) + ") of " + o->model + " with its model (" + rpc_form_name(src.form) + ") -> " +
                  o->output);
        return 0;
      }
      if (!o->window.empty()) throw UsageError("--window goes with crop");
      check_outputs({{"-o", o->output}}, {o->model, o->input, o->dem});
      const RpcSource src = load_rpc_model(o->model);
      GeoGrid dem;
      if (!o->dem.empty()) {
        const GeoBounds box = model_bounds(src.model);
        dem = read_geotiff_grid(o->dem, &box);
      }
      const RpcPointDirection dir = o->action == "project" ? RpcPointDirection::Project : RpcPointDirection::Localize;
      RpcPointStats st;
      std::string text;
      if (o->input == "-") {
        text = transform_rpc_points(std::cin, "stdin", src.model, dir, o->dem.empty() ? nullptr : &dem, &st);
      } else {
        std::ifstream in = open_input_file(o->input);
        text = transform_rpc_points(in, o->input, src.model, dir, o->dem.empty() ? nullptr : &dem, &st);
      }
      AtomicOutput out(o->output);
      out.stream() << text;
      out.commit();
      if (!o->quiet)
        summary(o->action + " through " + src.path + " (" + rpc_form_name(src.form) + "): " + std::to_string(st.points) +
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
