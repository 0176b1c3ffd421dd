// The summary box at the top of a tp-report page: a run read at a glance from the files it was given.
// Each line from one kind of file, its figures taken from the records where they are counts and from the
// summary lines the writing tool put in the header where they are its statistics:
//   matches        total over the pair files, pairs, least and most per pair, share with refined = 1
//                  (tp-match's least-squares positions; only when the files have the column)
//   tracks         per tracks file: tracks, and tracks by the number of views they are seen in
//   adjustment     per rpc-residuals file: rms_before_px -> rms_after_px (and without the flagged
//                  tracks), observations, check_rms_px when the run had check tracks
//   flagged        per rpc-residuals file: flagged_tracks of tracks; without one, per ground file with a
//                  flagged column: its records with flagged = 1
//   check points   per accuracy file: check points' rmse_h_m and rmse_v_m before -> after
//   trifocal fit   per residuals file: rmse_px of the fit tracks and check_rmse_px of the held-out ones
// Shares are printed with one decimal ("%.1f" of the percentage); statistics of the header lines with 3
// significant digits ("%.3g"; "%.0f" from 1000 on), counts as written.
#pragma once
#include <string>
#include <vector>

#include "tpkit/core/text_table.hpp"

namespace tpkit {

struct SummaryLine {
  std::string key;     // "matches", "tracks", "adjustment", "flagged", "check points", "trifocal fit"
  std::string source;  // the file's name (several files of a kind: one line each)
  std::string text;    // plain text, e.g. "4210 in 3 pairs (1200 to 1630 per pair), 97.1% refined"
  std::string id;      // element id of its value on the page: s-matches, s-tracks-1, ...
};

// The lines, in the order above, of the tables read (files that could not be read are left out).
std::vector<SummaryLine> run_summary(const std::vector<const TextTable*>& tables);

// The box: <section id="summary" class="glance"> with one table row per line, or "" for no line.
std::string run_summary_html(const std::vector<SummaryLine>& lines);

}  // namespace tpkit
