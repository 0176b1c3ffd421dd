// The man-page renderer behind every tool's --help.
#include <gtest/gtest.h>

#include "tpkit/core/tool_support.hpp"

TEST(ToolSupport, RendersTheRoffSubset) {
  const char* page =
      ".TH TP-FOO 1 \"2026\" tpkit\n"
      ".SH NAME\n"
      "tp-foo \\- does foo\n"
      ".SH SYNOPSIS\n"
      ".B tp-foo\n"
      "[\\fB\\-o\\fR \\fIOUT\\fR]\n"
      ".SH OPTIONS\n"
      ".TP\n"
      ".BR \\-o \", \" \\-\\-output \" FILE\"\n"
      "Write to FILE, taper\\[u00B2] times 5\\[u00B0] at La R\\['e]union.\n"
      ".nf\n"
      "  a   b\n"
      ".fi\n";
  std::string t = tpkit::render_man_page(page);
  EXPECT_NE(t.find("TP-FOO(1)"), std::string::npos) << t;
  EXPECT_NE(t.find("tp-foo - does foo"), std::string::npos) << t;
  EXPECT_NE(t.find("-o, --output FILE"), std::string::npos) << t;
  EXPECT_NE(t.find("           Write to FILE, taper\u00b2 times 5\u00b0 at La R\u00e9union."), std::string::npos) << t;
  EXPECT_NE(t.find("  a   b"), std::string::npos) << t;
  EXPECT_EQ(t.find("\\f"), std::string::npos) << t;
}
