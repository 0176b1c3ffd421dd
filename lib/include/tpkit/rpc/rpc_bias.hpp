// Image-space bias of an RPC camera (Fraser & Hanley 2003; Grodecki & Dial 2003): the corrected projection
// of ground point g is q = p + d(p), p = rpc.project(g) (tpkit pixels), with
//   dx = a[0] + a[1] x + a[2] y,   dy = b[0] + b[1] x + b[2] y        (x, y = p; linear terms per pixel)
// Models: shift = a[0], b[0] (2 terms); drift = shift + the terms linear in the line (row) y: a[2], b[2]
// (4 terms); affine = all 6.
#pragma once
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "tpkit/core/text_table.hpp"

namespace tpkit {

enum class BiasModel { shift, drift, affine };
// "shift" | "drift" | "affine"; UsageError otherwise.
BiasModel parse_bias_model(const std::string&);
const char* bias_model_name(BiasModel);
// Which of the 6 terms (a0 a1 a2 b0 b1 b2) the model estimates.
std::array<bool, 6> bias_terms_used(BiasModel);

struct ImageBias {
  std::array<double, 3> a{}, b{};
  Eigen::Vector2d offset(const Eigen::Vector2d& p) const {
    return {a[0] + a[1] * p[0] + a[2] * p[1], b[0] + b[1] * p[0] + b[2] * p[1]};
  }
  Eigen::Vector2d apply(const Eigen::Vector2d& p) const { return p + offset(p); }
  bool zero() const { return a == std::array<double, 3>{} && b == std::array<double, 3>{}; }
};

// Comma-separated finite numbers ("1.5,-2,3e-4"); UsageError "OPTION: 'ITEM' is not a number (expected FORM)".
std::vector<double> parse_number_list(const std::string& text, const std::string& option, const std::string& form);

// "dx,dy[,dxy,dyy[,dxx,dyx]]" (pixels, then per pixel): shift, then the drift terms a[2] = d(dx)/dy and
// b[2] = d(dy)/dy, then the remaining affine terms a[1] = d(dx)/dx and b[1] = d(dy)/dx. UsageError naming
// `option` when malformed.
ImageBias parse_image_bias(const std::string& text, const std::string& option);

// The rpc-bias file (man/tpkit-formats.5): "# tpkit rpc-bias 1", the images, then one record per image
// "image a0 a1 a2 b0 b1 b2" (image numbered from 1; terms as above), extra columns allowed after them.
// tp-synth writes the injected biases (truth.bias), rpc-adjust the estimated ones.
struct BiasTable {
  std::vector<ImageRef> images;
  Meta meta;
  std::vector<ImageBias> bias;  // per image, in the order of `images`
  std::vector<std::string> extra_names;
  std::vector<std::vector<double>> extra;  // per image
};
void save_bias_table(const std::string& path, const BiasTable&);
BiasTable read_bias_table(const std::string& path);

}  // namespace tpkit
