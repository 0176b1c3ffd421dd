// RPC00B models in the files that carry them (man/tpkit-formats.5, "RPC camera models"):
//
//   tiff    GeoTIFF tag 50844 (RPCCoefficientTag, 92 doubles) inside the image
//   nitf    the RPC00B (or RPC00A) TRE of a NITF image (rpc_nitf.hpp), inside the image (.NTF, .NITF)
//   txt     GDAL / Ikonos key-value sidecar IMAGE_rpc.txt or IMAGE_RPC.TXT ("LINE_OFF: 5720.5", one per line,
//           LINE_NUM_COEFF_1 .. _20 etc.; a unit word after a value is allowed)
//   rpb     DigitalGlobe / Maxar IMAGE.RPB (BEGIN_GROUP = IMAGE ... lineOffset = ...; lineNumCoef = ( ... );)
//   dimap   Pléiades / SPOT DIMAP v2 RPC_*.XML (Global_RFM: Direct_Model, Inverse_Model, RFM_Validity), v3
//           (Pléiades Neo: ImagetoGround_Values, GroundtoImage_Values) and v1 (the first Pléiades products'
//           PHRDIMAP.XML: Inverse_Model F_COL / F_ROW and Direct_Model F_LON / F_LAT, 40 numbers each,
//           RFM_Validity Lon / Lat / Alt / Col / Row with A = scale, B = offset)
//   geom    OSSIM keyword list IMAGE.geom ("line_off: 5720.5", line_num_coeff_00 .. _19 etc.) of an
//           ossimRpcModel, as OSSIM, OTB, CARS and shareloc write it, or of the models saved through it
//           (OTB's ossimPleiadesModel, ossimSpot6Model: the RPC keys at the top, DIMAP metadata under
//           support_data.); polynomial_format B (RPC00B) or A (RPC00A's term order, reordered when read)
//   aux     GDAL's PAM sidecar IMAGE.ext.aux.xml, its RPC metadata domain (<Metadata domain="RPC">, one
//           <MDI key="LINE_OFF"> per key, each polynomial's 20 coefficients in one value)
//
// Pixel convention: RPC00B (tiff, nitf, txt, rpb), GDAL's RPC metadata (aux) and OSSIM's image space (geom)
// have (0, 0) at the centre of the top-left pixel, as tpkit: taken as they are. DIMAP v1 and v2 number
// pixels from 1 (the centre of the top-left pixel is (1, 1)): their SAMP_OFF and LINE_OFF (v1: Col.B and
// Row.B; and the validity domain's rows and columns) are 1 more than tpkit's; v3 counts from FIRST_COL /
// FIRST_ROW (0 or 1). The conversion happens here only.
// Every writer writes numbers in the shortest form that reads back to the same double, so that
// write -> read is exact; every reader refuses a malformed file with InputError(file:line: reason).
#pragma once
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "tpkit/rpc/rpc_model.hpp"

namespace tpkit {

enum class RpcForm { tiff, nitf, txt, rpb, dimap, geom, aux };
// "tiff", "nitf", "txt", "rpb", "dimap", "geom", "aux"
const char* rpc_form_name(RpcForm);
// The form of a file, from its name: *.RPB -> rpb, *.txt / *.TXT -> txt, *.aux.xml -> aux (before the
// next rule), *.XML -> dimap, *.geom -> geom, *.tif / *.tiff -> tiff.
// Throws InputError when the name tells nothing.
RpcForm rpc_form_of(const std::string& path);

// Readers of each form. read_rpc_tiff returns nothing when the TIFF has no RPC tag.
RpcModel read_rpc_txt(const std::string& path);
RpcModel read_rpc_rpb(const std::string& path);
RpcModel read_rpc_dimap(const std::string& path);
RpcModel read_rpc_geom(const std::string& path);
// Nothing when the .aux.xml has no RPC metadata domain (GDAL writes them for statistics too).
std::optional<RpcModel> read_rpc_aux(const std::string& path);
std::optional<RpcModel> read_rpc_tiff(const std::string& path);
// A NITF image's RPC00B / RPC00A TRE; nothing when it has neither.
std::optional<RpcModel> read_rpc_ntf(const std::string& path);
// Any form, chosen by rpc_form_of(); a TIFF without the tag, an .aux.xml without the domain is an InputError.
RpcModel read_rpc_file(const std::string& path);

// Writers (atomic, atomic_output.hpp). DIMAP needs a direct model: when the model has none, one is fitted
// to it over its normalization volume (fit_direct_model).
void write_rpc_txt(const std::string& path, const RpcModel&);
void write_rpc_rpb(const std::string& path, const RpcModel&);
void write_rpc_dimap(const std::string& path, const RpcModel&);
// An ossimRpcModel keyword list (polynomial_format B).
void write_rpc_geom(const std::string& path, const RpcModel&);
// A PAM file holding the RPC metadata domain only (written whole: other PAM metadata is not kept).
void write_rpc_aux(const std::string& path, const RpcModel&);
// A copy of the TIFF `image` with the model in tag 50844 (every other tag and the pixels kept).
void write_rpc_tiff_copy(const std::string& image, const std::string& out, const RpcModel&);
void write_rpc_file(const std::string& path, RpcForm, const RpcModel&);

// The 92 values of tag 50844 (image_io.hpp RpcTagValues) of a model, and back.
std::array<double, 92> rpc_tag_values(const RpcModel&);
RpcModel rpc_from_tag_values(const std::array<double, 92>&);

// Text of the txt / rpb / dimap / geom / aux forms (what the writers write).
std::string format_rpc_txt(const RpcModel&);
std::string format_rpc_rpb(const RpcModel&);
std::string format_rpc_dimap(const RpcModel&);
std::string format_rpc_geom(const RpcModel&);
std::string format_rpc_aux(const RpcModel&);

// The model with a direct model (image -> ground) fitted to its inverse over its normalization volume.
RpcModel with_direct_model(const RpcModel&);

// Sidecar names beside an image, in the order they are looked for: IMAGE.ext.aux.xml (GDAL's PAM file:
// named after this very file, and where GDAL users set or correct a model while the vendor's sidecar stays
// as delivered, so it comes first; one without an RPC domain is passed over), IMAGE_rpc.txt,
// IMAGE_RPC.TXT, IMAGE.RPB, IMAGE.rpb, IMAGE.geom (OTB writes it beside its output image), and for DIMAP
// images named IMG_NAME.ext (optionally with a _R<i>C<j> tile suffix) RPC_NAME.XML, then PHRDIMAP.XML
// (DIMAP v1 products: one PHRDIMAP.XML beside IMG_R1C1.JP2 ..., where OTB looks for it).
std::vector<std::string> rpc_sidecar_candidates(const std::string& image);

// Where an image's model comes from: an explicit file (overrides, keyed by the image path as given), else
// the image's own tag 50844, else the first sidecar found (rpc_sidecar_candidates).
struct RpcSource {
  RpcModel model;
  std::string path;  // the file read (the image itself for the tag)
  RpcForm form = RpcForm::tiff;
};
// Nothing when the image has no model anywhere. `overrides` are keyed by the image as given
// (resolve_rpc_overrides): the override of `image` is the one under that very name.
std::optional<RpcSource> find_image_rpc(const std::string& image, const std::map<std::string, std::string>& overrides = {});
// The same, throwing InputError("IMAGE: no RPC model: no tag 50844 and none of SIDECARS") when there is none.
RpcSource load_image_rpc(const std::string& image, const std::map<std::string, std::string>& overrides = {});
// The model of an image or of a model file: a name of a model form (_rpc.txt / .TXT, .RPB, .XML, .aux.xml,
// .geom) is read as that form, anything else as an image (load_image_rpc: its tag 50844, else a sidecar).
RpcSource load_rpc_model(const std::string& image_or_model);
// "--rpc IMG=FILE" values -> map image -> file; UsageError for a value without '='.
std::map<std::string, std::string> parse_rpc_overrides(const std::vector<std::string>& values);
// The index in `images` of the image that `ref` names, the one rule for every reference to a given image
// (a tracks or GCP file's image lines, --rpc IMAGE=FILE, --fixed): the same path as written, else the same
// file (found as written or, for a file's reference, relative to the folder of `listed_in`, the file that
// names it), else the one image of that file name. -1 when none matches, -2 when several share the name.
int image_index(const std::string& ref, const std::vector<std::string>& images, const std::string& listed_in = "");
// The --rpc overrides keyed by the image of `images` each names (image_index: "./a.tif" names a.tif).
// UsageError for an IMAGE that is not one of them (a typo is not ignored) and for two that name one image.
std::map<std::string, std::string> resolve_rpc_overrides(const std::map<std::string, std::string>& overrides,
                                                         const std::vector<std::string>& images);

}  // namespace tpkit
