// SPDX-License-Identifier: Apache-2.0
// The report's baselines, residual histograms, intrinsics table and readable plots (issue 37
// §7), read back from the page: each section's numbers against what they are made of.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "report/history_fixture.h"
#include "rigcal/base/format.h"
#include "rigcal/io/provenance.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/report/report_html.h"
#include "rigcal/report/report_input.h"

namespace rigcal::report::report_test {
namespace {

using ::testing::HasSubstr;

class ReportExtrasTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { files_ = new HistoryFiles(MakeHistory("extras")); }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(files_->dir);
    delete files_;
  }
  static std::string Write(const std::string& name, const std::string& text) {
    const std::string path = (files_->dir / name).string();
    std::ofstream(path) << text;
    return path;
  }
  static HistoryFiles* files_;
};
HistoryFiles* ReportExtrasTest::files_ = nullptr;

// The text of `html` from `start` up to `end` (exclusive); empty without `start`.
std::string Element(const std::string& html, const std::string& start, const std::string& end) {
  const size_t at = html.find(start);
  if (at == std::string::npos) return "";
  const size_t stop = html.find(end, at);
  return html.substr(at, stop == std::string::npos ? std::string::npos : stop - at);
}

// The contents of the cell <td class="cls"> in `row`.
std::string Cell(const std::string& row, const std::string& cls) {
  const std::regex re("<td class=\"" + cls + "\">([^<]*)</td>");
  std::smatch m;
  return std::regex_search(row, m, re) ? m[1].str() : "";
}

// "value ± sigma" as two numbers.
std::pair<double, double> ValueAndSigma(const std::string& text) {
  const size_t pm = text.find(" ± ");
  if (pm == std::string::npos) return {NAN, NAN};
  return {std::stod(text.substr(0, pm)), std::stod(text.substr(pm + 4))};
}

std::string Attribute(const std::string& element, const std::string& name) {
  const std::regex re(" data-" + name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(element, m, re) ? m[1].str() : "";
}

template <typename T>
std::vector<T> Numbers(const std::string& text) {
  std::vector<T> out;
  std::istringstream in(text);
  for (T v; in >> v;) out.push_back(v);
  return out;
}

// σ of |C| from the per-axis σ, first order (report_tables.h), computed here from the terms.
double NormSigma(const Eigen::Vector3d& C, const Eigen::Vector3d& s) {
  double sum = 0.0;
  for (int k = 0; k < 3; ++k) sum += C[k] * C[k] * s[k] * s[k];
  return std::sqrt(sum) / C.norm();
}

TEST_F(ReportExtrasTest, BaselineIsTheNormOfCInItsUnitAndInMetresWhenKnown) {
  auto data = LoadReport({files_->history_log, "", ""});
  ASSERT_TRUE(data.ok()) << data.error();
  std::string html = RenderReportHtml(*data);
  // The unit is not known: |C| in master units and a sentence that says so, no metres column.
  EXPECT_THAT(html, HasSubstr("<p class=\"source unit\">C is in master units"));
  EXPECT_EQ(CountOf(html, "<td class=\"metres\">"), 0);
  for (const SlaveCalibration& s : data->final_result.slaves) {
    ASSERT_TRUE(s.usable()) << s.name;
    const std::string row = Element(html, "<tr data-slave=\"" + s.name + "\">", "</tr>");
    const auto [norm, sigma] = ValueAndSigma(Cell(row, "unit"));
    EXPECT_NEAR(norm, s.estimate.C.norm(), 0.5e-4) << row;
    const double expected_sigma = NormSigma(s.estimate.C, s.pos_std);
    ASSERT_TRUE(std::isfinite(expected_sigma));
    EXPECT_NEAR(sigma, expected_sigma, 0.05 * expected_sigma) << row;  // 2 significant digits
  }

  // A metric truth (the drive's C times 2.5 m per unit): the baseline in metres is |C| times
  // the master unit fitted to it.
  std::map<std::string, Similarity> metric = files_->truth_rig;
  for (auto& [name, t] : metric) t.C *= 2.5;
  const std::string truth = (files_->dir / "metric_truth.yaml").string();
  ASSERT_TRUE(io::WriteRigYaml(truth, metric).ok());
  data = LoadReport({files_->history_log, "", truth});
  ASSERT_TRUE(data.ok()) << data.error();
  ASSERT_NEAR(data->metres_per_unit, 2.5, 0.025);
  html = RenderReportHtml(*data);
  EXPECT_EQ(CountOf(html, "<td class=\"metres\">"), 2);
  for (const SlaveCalibration& s : data->final_result.slaves) {
    const std::string row = Element(html, "<tr data-slave=\"" + s.name + "\">", "</tr>");
    const auto [metres, metres_sigma] = ValueAndSigma(Cell(row, "metres"));
    EXPECT_NEAR(metres, s.estimate.C.norm() * data->metres_per_unit, 0.5e-4) << row;
    EXPECT_NEAR(metres_sigma, NormSigma(s.estimate.C, s.pos_std) * data->metres_per_unit,
                0.05 * metres_sigma)
        << row;
    EXPECT_THAT(row, HasSubstr("fitted to the truth"));
  }

  // A metric master in the config: C is metres, the baseline |C| itself.
  const std::string config = Write("metric_master.yaml",
                                   "rig: {name: r, master: cam0}\n"
                                   "cameras:\n  - {name: cam0, metric: true}\n"
                                   "  - {name: cam1}\n  - {name: cam2}\n");
  auto metric_master = LoadReport({files_->history_log, "", "", config});
  ASSERT_TRUE(metric_master.ok()) << metric_master.error();
  EXPECT_EQ(metric_master->metres_per_unit, 1.0);
  html = RenderReportHtml(*metric_master);
  const SlaveCalibration& cam1 = metric_master->final_result.slaves[0];
  const std::string row = Element(html, "<tr data-slave=\"cam1\">", "</tr>");
  EXPECT_NEAR(ValueAndSigma(Cell(row, "metres")).first, cam1.estimate.C.norm(), 0.5e-4) << row;
  EXPECT_THAT(row, HasSubstr("metric master"));
}

// A result file whose provenance says C is in metres (a metric master, a target reference,
// --metric-*): the baseline in metres is |C| itself; without that line, the unit is unknown.
TEST_F(ReportExtrasTest, ResultInMetresGivesTheBaselineInMetres) {
  auto history = LoadReport({files_->history_log, "", ""});
  ASSERT_TRUE(history.ok()) << history.error();
  io::Provenance provenance;
  provenance.metric = true;
  const std::string metric = Write("metric_result.yaml", io::ResultToYaml(history->final_result) +
                                                             io::ProvenanceToYaml(provenance));
  auto data = LoadReport({metric, "", ""});
  ASSERT_TRUE(data.ok()) << data.error();
  EXPECT_EQ(data->metres_per_unit, 1.0);
  EXPECT_EQ(data->distance_unit, "m");
  const std::string html = RenderReportHtml(*data);
  const SlaveCalibration& cam2 = data->final_result.slaves[1];
  const std::string row = Element(html, "<tr data-slave=\"cam2\">", "</tr>");
  EXPECT_NEAR(ValueAndSigma(Cell(row, "metres")).first, cam2.estimate.C.norm(), 0.5e-4) << row;
  EXPECT_THAT(row, HasSubstr("(the result&apos;s provenance)"));  // XML-escaped

  provenance.metric = false;
  const std::string odometry =
      Write("odometry_result.yaml",
            io::ResultToYaml(history->final_result) + io::ProvenanceToYaml(provenance));
  auto unknown = LoadReport({odometry, "", ""});
  ASSERT_TRUE(unknown.ok()) << unknown.error();
  EXPECT_TRUE(std::isnan(unknown->metres_per_unit));
  EXPECT_EQ(CountOf(RenderReportHtml(*unknown), "<td class=\"metres\">"), 0);
}

TEST_F(ReportExtrasTest, HistogramsCountEveryResidualWithItsSigma) {
  auto data = LoadReport({files_->history_log, files_->pose_log, ""});
  ASSERT_TRUE(data.ok()) << data.error();
  ASSERT_TRUE(data->motions.has_value());
  const std::string html = RenderReportHtml(*data);
  for (const std::string& slave : data->slaves) {
    const std::vector<MotionSample>& samples = data->motions->slaves.at(slave).samples;
    const std::string figure = Element(html, "data-plot=\"histograms-" + slave + "\"", ">");
    ASSERT_FALSE(figure.empty()) << slave;
    EXPECT_EQ(std::stoul(Attribute(figure, "residuals")), samples.size());
    for (const std::string quantity : {"rotation", "position"}) {
      const bool rotation = quantity == std::string("rotation");
      const std::string suffix = rotation ? "-deg" : "";
      const auto edges = Numbers<double>(Attribute(figure, quantity + "-edges" + suffix));
      const auto counts = Numbers<int>(Attribute(figure, quantity + "-counts"));
      ASSERT_EQ(edges.size(), counts.size() + 1) << figure;
      ASSERT_GE(counts.size(), 5u);
      // The counts add up to every residual, and each bin holds the residua within its edges.
      int total = 0;
      for (int c : counts) total += c;
      EXPECT_EQ(total, static_cast<int>(samples.size())) << slave << " " << quantity;
      std::vector<int> expected(counts.size(), 0);
      double squares = 0.0;
      for (const MotionSample& m : samples) {
        const double v = rotation ? m.rotation_deg : m.position_abs;
        squares += v * v;
        size_t b = 0;
        while (b + 1 < counts.size() && v >= edges[b + 1]) ++b;
        ++expected[b];
      }
      EXPECT_EQ(counts, expected) << slave << " " << quantity;
      const double sigma = std::stod(Attribute(figure, quantity + "-sigma" + suffix));
      EXPECT_NEAR(sigma, std::sqrt(squares / samples.size()), 1e-12 * sigma);
      for (const MotionSample& m : samples) {
        EXPECT_LE(rotation ? m.rotation_deg : m.position_abs, edges.back());
      }
    }
    // Drawn: the counts as a series, σ as a dashed line, axes labelled with units.
    const std::string svg = Element(html, "data-plot=\"histograms-" + slave + "\"", "</figure>");
    EXPECT_THAT(svg, HasSubstr("angle [deg]"));
    EXPECT_THAT(svg, HasSubstr("|residual| [master units]"));
    EXPECT_THAT(svg, HasSubstr("motions per bin"));
    EXPECT_EQ(CountOf(svg, "data-label=\"σ (RMS)"), 2);
  }
}

TEST_F(ReportExtrasTest, IntrinsicsTableIsTheConfigs) {
  const std::string config =
      Write("intrinsics.yaml",
            "rig: {name: r, master: cam0}\ncameras:\n"
            "  - {name: cam0, model: pinhole, resolution: [752, 480],\n"
            "     intrinsics: [651.25, 650.5, 375.5, 239.5], distortion: [-0.28, 0.07, 0.0002, "
            "1.76e-05]}\n"
            "  - {name: cam1, model: fisheye, resolution: [1280, 1024],\n"
            "     intrinsics: [380.1, 380.2, 640.3, 511.7], distortion: [0.01, -0.002, 0.0003, "
            "-4e-05]}\n"
            "  - {name: cam2}\n");
  auto data = LoadReport({files_->history_log, "", "", config});
  ASSERT_TRUE(data.ok()) << data.error();
  auto rig = io::LoadRigConfig(config);
  ASSERT_TRUE(rig.ok()) << rig.error();
  const std::string html = RenderReportHtml(*data);
  const std::string table = Element(html, "<table class=\"final intrinsics\">", "</table>");
  EXPECT_EQ(CountOf(table, "<tr data-camera="), 2);  // cam2 has no intrinsics
  for (const io::CameraConfig& camera : rig->cameras) {
    if (!camera.spec) continue;
    const camera::CameraSpec& spec = *camera.spec;
    const std::string row = Element(table, "<tr data-camera=\"" + camera.name + "\">", "</tr>");
    ASSERT_FALSE(row.empty()) << camera.name;
    EXPECT_THAT(row, HasSubstr(std::string(camera::ModelName(spec.model))));
    const auto projection = Numbers<double>(Cell(row, "projection"));
    ASSERT_EQ(projection.size(), 4u) << row;
    for (int i = 0; i < 4; ++i) EXPECT_EQ(projection[i], spec.intrinsics[i]) << row;
    EXPECT_EQ(Numbers<double>(Cell(row, "distortion")), spec.distortion) << row;
    EXPECT_EQ(Cell(row, "resolution"),
              std::to_string(spec.width) + " × " + std::to_string(spec.height));
  }
  // Without a config the section says how to get it.
  auto without = LoadReport({files_->history_log, "", ""});
  ASSERT_TRUE(without.ok());
  EXPECT_THAT(RenderReportHtml(*without), HasSubstr("no rig config given (--config)"));
}

// The series in `panel` (SVG text from a panel's start): (label, style) per series, the style
// being "colour|dash pattern|marker element".
std::vector<std::pair<std::string, std::string>> SeriesStyles(const std::string& panel) {
  std::vector<std::pair<std::string, std::string>> out;
  const std::string start = "<g class=\"series\" data-label=\"";
  for (size_t at = panel.find(start); at != std::string::npos; at = panel.find(start, at + 1)) {
    const size_t label_end = panel.find('"', at + start.size());
    const size_t end = panel.find("</g>", at);
    const std::string body = panel.substr(at, end - at);
    std::smatch colour, dash, marker;
    std::regex_search(body, colour, std::regex("(stroke|fill)=\"(#[0-9A-Fa-f]{6})\""));
    std::regex_search(body, dash, std::regex("stroke-dasharray=\"([^\"]*)\""));
    std::regex_search(body, marker, std::regex("<(circle|rect|polygon|path) "));
    out.emplace_back(panel.substr(at + start.size(), label_end - at - start.size()),
                     colour.str(2) + "|" + dash.str(1) + "|" + marker.str(1));
  }
  return out;
}

TEST_F(ReportExtrasTest, CameraLinesDifferInColourAndDashOrMarkerWithLegendAndUnits) {
  auto data = LoadReport({files_->history_log, files_->pose_log, ""});
  ASSERT_TRUE(data.ok()) << data.error();
  const std::string html = RenderReportHtml(*data);
  // The C₀ᵀr₀ panel: axes with units, the master and the slave in their own colour and marker.
  const std::string scales = Element(html, "data-plot=\"scales-cam1\"", "</figure>");
  const size_t dots_at = scales.find("C₀ᵀr₀ and Cᵢᵀrᵢ per motion");
  ASSERT_NE(dots_at, std::string::npos);
  const std::string dots = scales.substr(scales.rfind("<g class=\"panel\">", dots_at));
  EXPECT_THAT(dots, HasSubstr("time [s]"));
  EXPECT_THAT(dots, HasSubstr("Cᵀr [odometry unit of each camera]"));
  const auto dot_series = SeriesStyles(dots);
  ASSERT_EQ(dot_series.size(), 2u);
  EXPECT_EQ(dot_series[0].first, "cam0: C₀ᵀr₀ [master unit]");
  EXPECT_EQ(dot_series[1].first, "cam1: Cᵢᵀrᵢ [cam1 unit]");
  const auto part = [](const std::string& style, int i) {
    std::vector<std::string> parts;
    std::stringstream in(style);
    for (std::string p; std::getline(in, p, '|');) parts.push_back(p);
    while (parts.size() < 3) parts.push_back("");
    return parts[i];
  };
  EXPECT_NE(part(dot_series[0].second, 0), part(dot_series[1].second, 0));  // colour
  EXPECT_NE(part(dot_series[0].second, 2), part(dot_series[1].second, 2));  // marker
  EXPECT_THAT(dots, HasSubstr("class=\"legend\""));
  // The health lines: one per camera, each with its own colour and its own dash pattern and
  // marker, named in a legend.
  const std::string health = Element(html, "data-plot=\"camera-health\"", "</figure>");
  const auto lines = SeriesStyles(health.substr(health.find("<g class=\"panel\">")));
  ASSERT_GE(lines.size(), 3u);
  std::set<std::string> colours, patterns;
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(lines[i].first, data->cameras[i]);
    colours.insert(part(lines[i].second, 0));
    patterns.insert(part(lines[i].second, 1) + "/" + part(lines[i].second, 2));
  }
  EXPECT_EQ(colours.size(), 3u);
  EXPECT_EQ(patterns.size(), 3u);
  EXPECT_THAT(health, HasSubstr("class=\"legend\""));
}

}  // namespace
}  // namespace rigcal::report::report_test
