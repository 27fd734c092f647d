// SPDX-License-Identifier: Apache-2.0
#include "rigcal/plot/svg_plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace rigcal {
namespace {

int Count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (size_t pos = text.find(needle); pos != std::string::npos;
       pos = text.find(needle, pos + needle.size())) {
    ++n;
  }
  return n;
}

// Every opening tag has a matching closing tag (or is self-closing), in nesting order.
bool TagsBalanced(const std::string& svg) {
  std::vector<std::string> stack;
  size_t pos = 0;
  while ((pos = svg.find('<', pos)) != std::string::npos) {
    size_t end = svg.find('>', pos);
    if (end == std::string::npos) return false;
    std::string tag = svg.substr(pos + 1, end - pos - 1);
    pos = end + 1;
    if (tag.empty() || tag[0] == '?' || tag[0] == '!') continue;
    if (tag[0] == '/') {
      std::string name = tag.substr(1);
      if (stack.empty() || stack.back() != name) return false;
      stack.pop_back();
    } else if (tag.back() != '/') {
      stack.push_back(tag.substr(0, tag.find_first_of(" \n")));
    }
  }
  return stack.empty();
}

plot::PlotFigure TwoPanelFigure() {
  plot::PlotFigure figure;
  figure.title = "errors <a & b>";
  plot::PlotPanel a;
  a.title = "rotation";
  a.x_label = "eps [deg]";
  a.y_label = "error [deg]";
  a.series.push_back({"mean \"lls\"", {0, 1, 2, 3}, {0, 1.1, 2.05, 3.2}, "", false, true});
  a.series.push_back({"bound", {0, 1, 2, 3}, {0, 0.5, 1.0, 1.5}, "", true, false});
  plot::PlotPanel b;
  b.title = "with gaps";
  b.series.push_back({"gappy", {0, 1, 2, 3, 4}, {1, NAN, 3, 4, INFINITY}, "#123456", false, true});
  b.series.push_back({"empty", {}, {}, "", false, true});
  figure.panels = {a, b};
  return figure;
}

TEST(SvgPlotTest, XmlEscapeReplacesSpecialCharacters) {
  EXPECT_EQ(plot::XmlEscape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&apos;");
  EXPECT_EQ(plot::XmlEscape("plain text 1.5"), "plain text 1.5");
}

TEST(SvgPlotTest, NiceTicksCoverRangeWithRoundSteps) {
  for (auto [lo, hi] : std::vector<std::pair<double, double>>{
           {0.0, 3.0}, {0.0, 25.0}, {0.013, 0.97}, {-4.2, 17.0}, {4.0, 24.0}, {0.0, 0.0021}}) {
    std::vector<double> ticks = plot::NiceTicks(lo, hi, 6);
    ASSERT_GE(ticks.size(), 2u) << lo << " " << hi;
    EXPECT_LE(ticks.front(), lo + 1e-12);
    EXPECT_GE(ticks.back(), hi - 1e-12);
    EXPECT_LE(ticks.size(), 12u);
    const double step = ticks[1] - ticks[0];
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    EXPECT_TRUE(std::abs(mantissa - 1) < 1e-6 || std::abs(mantissa - 2) < 1e-6 ||
                std::abs(mantissa - 5) < 1e-6)
        << "step " << step;
  }
}

TEST(SvgPlotTest, RendersWellFormedDocumentWithEverySeries) {
  const std::string svg = plot::RenderSvg(TwoPanelFigure());
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("<svg xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos);
  EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
  EXPECT_TRUE(TagsBalanced(svg));
  EXPECT_EQ(Count(svg, "<g class=\"series\""), 4);  // also the empty series
  EXPECT_EQ(Count(svg, "<g class=\"panel\">"), 2);
  // Title and labels are escaped, raw specials never appear in text.
  EXPECT_NE(svg.find("errors &lt;a &amp; b&gt;"), std::string::npos);
  EXPECT_NE(svg.find("mean &quot;lls&quot;"), std::string::npos);
  EXPECT_EQ(svg.find("<a & b>"), std::string::npos);
  // The gap splits the third series into two polylines; the infinite point is dropped.
  const size_t gappy = svg.find("data-label=\"gappy\"");
  const size_t gappy_end = svg.find("</g>", gappy);
  EXPECT_EQ(Count(svg.substr(gappy, gappy_end - gappy), "<polyline"), 2);
  EXPECT_EQ(Count(svg.substr(gappy, gappy_end - gappy), "<circle"), 3);
  EXPECT_NE(svg.find("stroke-dasharray"), std::string::npos);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

TEST(SvgPlotTest, RenderingIsDeterministic) {
  EXPECT_EQ(plot::RenderSvg(TwoPanelFigure()), plot::RenderSvg(TwoPanelFigure()));
}

TEST(SvgPlotTest, GridLayoutSizesTheDocument) {
  plot::PlotFigure figure = TwoPanelFigure();
  figure.panels.push_back(figure.panels[0]);
  figure.columns = 2;
  figure.panel_width = 300;
  figure.panel_height = 200;
  const std::string svg = plot::RenderSvg(figure);
  // 2 columns x 2 rows plus the title band.
  EXPECT_NE(svg.find("width=\"600.00\" height=\"428.00\""), std::string::npos);
  EXPECT_TRUE(TagsBalanced(svg));
}

TEST(SvgPlotTest, WriteSvgWritesFileAndReportsErrors) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("svg_plot_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "figure.svg").string();
  const Status written = plot::WriteSvg(TwoPanelFigure(), path);
  ASSERT_TRUE(written.ok()) << written.message();
  std::ifstream file(path);
  std::stringstream content;
  content << file.rdbuf();
  EXPECT_EQ(content.str(), plot::RenderSvg(TwoPanelFigure()));
  // No temporary file is left behind.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);

  const Status failed = plot::WriteSvg(TwoPanelFigure(), (dir / "missing" / "figure.svg").string());
  EXPECT_FALSE(failed.ok());
  EXPECT_NE(failed.message().find("missing"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// Lines told apart without colour: each series' marker shape and dash pattern, in the plot and
// in its legend entry.
TEST(SvgPlotTest, MarkersAndDashPatternsAreDrawnInPlotAndLegend) {
  plot::PlotPanel panel;
  const plot::Marker shapes[] = {plot::Marker::kSquare, plot::Marker::kTriangle,
                                 plot::Marker::kDiamond, plot::Marker::kCross};
  const char* elements[] = {"<rect ", "<polygon ", "<polygon ", "<path "};
  for (int i = 0; i < 4; ++i) {
    plot::PlotSeries s;
    s.label = "s" + std::to_string(i);
    s.x = {0.0, 1.0, 2.0};
    s.y = {1.0 * i, 1.0 * i + 1, 1.0 * i};
    s.marker = shapes[i];
    s.dash_array = std::to_string(i + 1) + " 3";
    panel.series.push_back(s);
  }
  plot::PlotFigure figure;
  figure.panels = {panel};
  const std::string svg = plot::RenderSvg(figure);
  EXPECT_TRUE(TagsBalanced(svg));
  for (int i = 0; i < 4; ++i) {
    const size_t at = svg.find("data-label=\"s" + std::to_string(i) + "\"");
    ASSERT_NE(at, std::string::npos);
    const std::string series = svg.substr(at, svg.find("</g>", at) - at);
    EXPECT_EQ(Count(series, elements[i]), 3) << series;  // one per point
    EXPECT_EQ(Count(series, "<circle"), 0);
    const std::string dash = "stroke-dasharray=\"" + std::to_string(i + 1) + " 3\"";
    EXPECT_EQ(Count(series, dash), 1);
    // The legend entry: the dashed line and the marker.
    const size_t legend = svg.find("<g class=\"legend\">");
    ASSERT_NE(legend, std::string::npos);
    EXPECT_EQ(Count(svg.substr(legend), dash), 1);
  }
  const size_t legend = svg.find("<g class=\"legend\">");
  const std::string entries = svg.substr(legend, svg.find("</g>", legend) - legend);
  EXPECT_EQ(Count(entries, "<path "), 1);
  EXPECT_EQ(Count(entries, "<polygon "), 2);
  EXPECT_EQ(Count(entries, "<rect "), 2);  // the legend's box and the square
}

}  // namespace
}  // namespace rigcal
