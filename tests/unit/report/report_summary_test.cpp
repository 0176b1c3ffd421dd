// The summary box's lines from tables made here with known counts: matches and their refined share, tracks by
// the number of views seen (nan views), an adjustment's statistics and flagged share as its header says them,
// a ground file's flagged records, check points; and the box's HTML (one id per figure, text escaped).
#include <gtest/gtest.h>

#include <cmath>

#include "tpkit/report/report_summary.hpp"

using namespace tpkit;

namespace {
TextTable table(const std::string& kind, const std::string& source, std::vector<std::string> columns, std::vector<std::vector<double>> rows) {
  TextTable t;
  t.kind = kind, t.source = source, t.columns = std::move(columns), t.rows = std::move(rows);
  return t;
}
const SummaryLine* find(const std::vector<SummaryLine>& lines, const std::string& id) {
  for (const auto& l : lines)
    if (l.id == id) return &l;
  return nullptr;
}
}  // namespace

TEST(RunSummary, MatchesTotalsAndRefinedShare) {
  // 3 + 5 matches, refined 1 1 0 | 1 1 1 0 1: 6 of 8
  const auto a = table("matches", "run/a.matches", {"id1", "x1", "y1", "id2", "x2", "y2", "refined"},
                       {{0, 1, 1, 0, 1, 1, 1}, {1, 1, 1, 1, 1, 1, 1}, {2, 1, 1, 2, 1, 1, 0}});
  const auto b = table("matches", "run/b.matches", {"id1", "x1", "y1", "id2", "x2", "y2", "refined"},
                       {{0, 1, 1, 0, 1, 1, 1}, {1, 1, 1, 1, 1, 1, 1}, {2, 1, 1, 2, 1, 1, 1}, {3, 1, 1, 3, 1, 1, 0}, {4, 1, 1, 4, 1, 1, 1}});
  const auto lines = run_summary({&a, &b});
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].id, "s-matches");
  EXPECT_EQ(lines[0].text, "8 matches in 2 pairs (3 to 5 per pair), 75.0% refined");
  // without the column: no share said
  const auto c = table("matches", "c.matches", {"x1", "y1", "x2", "y2"}, {{1, 1, 2, 2}});
  EXPECT_EQ(run_summary({&c})[0].text, "1 matches in 1 pair");
}

TEST(RunSummary, TracksByViewsSeen) {
  const double n = NAN;
  const auto t = table("tracks", "t.tracks", {"track", "x1", "y1", "x2", "y2", "x3", "y3"},
                       {{1, 1, 1, 2, 2, 3, 3}, {2, 1, 1, n, n, 3, 3}, {3, n, n, 2, 2, 3, 3}, {4, 1, 1, 2, 2, 3, 3}, {5, 1, 1, 2, 2, 3, 3}});
  const auto lines = run_summary({&t});
  const SummaryLine* l = find(lines, "s-tracks-1");
  ASSERT_NE(l, nullptr);
  EXPECT_EQ(l->text, "5 tracks (2 views: 2, 3 views: 3)");
  EXPECT_EQ(l->source, "t.tracks");
}

TEST(RunSummary, AdjustmentFlaggedAndCheckPointsFromTheHeaders) {
  auto r = table("rpc-residuals", "adj/rpc.residuals", {"track", "image", "x", "y"}, {{1, 1, 0, 0}, {1, 2, 0, 0}, {2, 1, 0, 0}});
  r.meta = {{"tracks", "40"}, {"rms_before_px", "3.2149"}, {"rms_after_px", "0.42"}, {"rms_after_unflagged_px", "0.30004"}, {"flagged_tracks", "3"}};
  auto acc = table("accuracy", "adj/accuracy", {"id"}, {});
  acc.meta = {{"check_before_n", "20"}, {"check_before_rmse_h_m", "1234.56"}, {"check_before_rmse_v_m", "6"},
              {"check_after_n", "20"},  {"check_after_rmse_h_m", "0.5"},  {"check_after_rmse_v_m", "0.9"}};
  auto g = table("ground", "adj/ground.points", {"track", "lon", "lat", "h", "flagged"}, {{1, 0, 0, 0, 0}, {2, 0, 0, 0, 1}, {3, 0, 0, 0, 0}, {4, 0, 0, 0, 0}});
  const auto lines = run_summary({&r, &acc, &g});
  ASSERT_NE(find(lines, "s-adjustment-1"), nullptr);
  EXPECT_EQ(find(lines, "s-adjustment-1")->text, "rms 3.21 px before, 0.42 px after (0.3 px without the flagged tracks), 3 observations");
  ASSERT_NE(find(lines, "s-flagged-1"), nullptr);
  EXPECT_EQ(find(lines, "s-flagged-1")->text, "3 of 40 tracks (7.5%)");
  EXPECT_EQ(find(lines, "s-flagged-2"), nullptr);  // the ground points of the same tracks: said once
  const auto alone = run_summary({&g});
  ASSERT_NE(find(alone, "s-flagged-1"), nullptr);
  EXPECT_EQ(find(alone, "s-flagged-1")->text, "1 of 4 ground points (25.0%)");
  ASSERT_NE(find(lines, "s-check-1"), nullptr);
  EXPECT_EQ(find(lines, "s-check-1")->text, "20 check points: horizontal rmse 1235 m before, 0.5 m after; vertical 6 m before, 0.9 m after");
  EXPECT_EQ(find(lines, "s-control-1"), nullptr);  // no control set in the file
}

TEST(RunSummary, BoxHtmlOneIdPerFigureTextEscaped) {
  EXPECT_EQ(run_summary_html({}), "");
  const std::string html = run_summary_html({{"tracks", "a<b>.tracks", "2 tracks", "s-tracks-1"}});
  EXPECT_NE(html.find("<section id=\"summary\" class=\"glance\">"), std::string::npos);
  EXPECT_NE(html.find("<td id=\"s-tracks-1\">2 tracks</td>"), std::string::npos);
  EXPECT_NE(html.find("a&lt;b&gt;.tracks"), std::string::npos);
  EXPECT_EQ(html.find("a<b>"), std::string::npos);
}
