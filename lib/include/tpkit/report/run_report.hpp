// One self-contained HTML page for the files of a run (tp-report): every tpkit file's header summary
// lines, and by kind: matches and tracks (counts per pair and per track length, coverage per image over
// its thumbnail), reproj-eval residuals (residual fields of the fit and check sets, histogram),
// rpc-adjust's rpc.residuals (fields before and after, histogram) and rpc.bias (the biases), ground points
// (their accuracy lines). Above them a summary box (report_summary.hpp) and, when given, the orthoimages
// before and after the adjustment (report_orthos.hpp). Figures are inline SVG, pictures inline JPEG; no
// network, no script.
#pragma once
#include <string>
#include <vector>

#include "tpkit/report/report_orthos.hpp"

namespace tpkit {

struct ReportOptions {
  std::string title = "tpkit run";
  bool coverage = true;  // coverage figures of matches and tracks (reads the images for thumbnails)
  // orthos (files; ortho_inputs) of before and after the adjustment; `orthos.images` is filled from the run
  std::vector<std::string> orthos_before, orthos_after;
  OrthoOptions orthos;
};

// The files a report covers: each argument a file, or a folder whose tpkit files (first line
// "# tpkit ", up to 3 levels down, sorted by path) are taken. InputError for an argument that does not
// exist, or when no tpkit file is found.
std::vector<std::string> report_inputs(const std::vector<std::string>& args);

// The page. A file that cannot be read is listed with its error (the page says so), not skipped. InputError
// for an ortho that cannot be shown (orthos_html): the orthos were asked for by name.
std::string run_report_html(const std::vector<std::string>& files, const ReportOptions& options);

}  // namespace tpkit
