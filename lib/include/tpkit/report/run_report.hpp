// One self-contained HTML page for the files of a run (tp-report): every tpkit file's header summary
// lines, and by kind: matches and tracks (counts per pair and per track length, coverage per image over
// its thumbnail), reproj-eval residuals (residual fields of the fit and check sets, histogram),
// rpc-adjust's rpc.residuals (fields before and after, histogram) and rpc.bias (the biases), ground points
// (their accuracy lines). Figures are inline SVG; no network, no script.
#pragma once
#include <string>
#include <vector>

namespace tpkit {

struct ReportOptions {
  std::string title = "tpkit run";
  bool coverage = true;  // coverage figures of matches and tracks (reads the images for thumbnails)
};

// The files a report covers: each argument a file, or a folder whose tpkit files (first line
// "# tpkit ", up to 3 levels down, sorted by path) are taken. InputError for an argument that does not
// exist, or when no tpkit file is found.
std::vector<std::string> report_inputs(const std::vector<std::string>& args);

// The page. A file that cannot be read is listed with its error (the page says so), not skipped.
std::string run_report_html(const std::vector<std::string>& files, const ReportOptions& options);

}  // namespace tpkit
