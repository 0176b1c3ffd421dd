// tp-rpc: single points through an image's RPC model, streamed (man/tp-rpc.1). Options -> library
// (rpc_io.hpp, rpc_points.hpp) -> stdout or a file.
#include <cmath>
#include <iostream>
#include <memory>

#include "tpkit/core/atomic_output.hpp"
#include "tpkit/core/error.hpp"
#include "tpkit/core/image_io.hpp"
#include "tpkit/core/input_file.hpp"
#include "tpkit/core/tool_support.hpp"
#include "tpkit/rpc/rpc_adjust.hpp"
#include "tpkit/rpc/rpc_io.hpp"
#include "tpkit/rpc/rpc_points.hpp"

extern const char* const tpkit_man_page;

namespace {
struct Opts {
  std::string action, model, input = "-", output = "-", dem;
  bool quiet = false;
};
}  // namespace

int main(int argc, char** argv) {
  using namespace tpkit;
  return run_tool("tp-rpc", argc, argv, [&](CLI::App& app) -> std::function<int()> {
    auto o = std::make_shared<Opts>();
    app.add_option("ACTION", o->action, "project (lon lat h -> x y h) | localize (x y h -> lon lat h)")
        ->required()
        ->check(CLI::IsMember({"project", "localize"}));
    app.add_option("MODEL", o->model, "an image (its tag 50844 or sidecar model) or a model file (_rpc.txt, .RPB, DIMAP .XML)")
        ->required();
    app.add_option("-i,--input", o->input, "points to transform; - for stdin (default)");
    app.add_option("-o,--output", o->output, "the transformed points; - for stdout (default)");
    app.add_option("--dem", o->dem, "localize onto this GeoTIFF DEM (EPSG:4326, heights above the ellipsoid, m): input x y");
    app.add_flag("-q,--quiet", o->quiet, "no summary on stderr");
    return [o]() {
      if (!o->dem.empty() && o->action != "localize") throw UsageError("--dem goes with localize");
      check_outputs({{"-o", o->output}}, {o->model, o->input, o->dem});
      const RpcSource src = load_rpc_model(o->model);
      GeoGrid dem;
      if (!o->dem.empty()) {
        const GeoBounds box{src.model.lon_off - std::fabs(src.model.lon_scale), src.model.lon_off + std::fabs(src.model.lon_scale),
                            src.model.lat_off - std::fabs(src.model.lat_scale), src.model.lat_off + std::fabs(src.model.lat_scale)};
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
