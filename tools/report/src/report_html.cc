// SPDX-License-Identifier: Apache-2.0
#include "rigcal/report/report_html.h"

#include <spdlog/fmt/fmt.h>

#include <cmath>
#include <sstream>

#include "report_plots.h"
#include "report_tables.h"
#include "rigcal/base/format.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/result_json.h"
#include "rigcal/io/truth_comparison.h"
#include "rigcal/plot/svg_plot.h"

namespace rigcal::report {
namespace {

using internal::ReportFigure;

constexpr const char* kStyle = R"(
body { font-family: "DejaVu Sans", Arial, Helvetica, sans-serif; font-size: 14px; margin: 24px;
       color: #222; }
h1 { font-size: 22px; margin-bottom: 4px; }
h2 { font-size: 18px; border-bottom: 1px solid #ccc; padding-bottom: 3px; margin-top: 28px; }
p.source { color: #555; margin-top: 0; }
ul.notes li { margin: 3px 0; }
div.table { overflow-x: auto; }
table.final { border-collapse: collapse; font-size: 12px; }
table.final th, table.final td { border: 1px solid #bbb; padding: 3px 5px; text-align: right; }
table.final td { white-space: nowrap; }
table.final th { white-space: normal; }
table.final th { background: #f0f0f0; }
table.final td.name, table.final td.text { text-align: left; }
table.final td.rotation { white-space: normal; min-width: 170px; text-align: left; }
table.final tr.truth td { color: #2a7a2a; }
table.final td.message { text-align: left; white-space: normal; max-width: 1100px; color: #555;
                         font-size: 12px; }
.state-converged { color: #1a7f1a; font-weight: bold; }
.state-usable { color: #1f5fa8; font-weight: bold; }
.state-initialising, .state-decalibrated { color: #b3261e; font-weight: bold; }
figure.plot { margin: 14px 0; }
figure.plot figcaption { font-weight: bold; margin-bottom: 2px; }
figure.plot p.note { color: #555; margin: 0 0 4px 0; font-size: 12px; }
figure.plot svg { max-width: 100%; height: auto; border: 1px solid #eee; }
figure.missing div.missing { padding: 18px; background: #f7f7f7; border: 1px dashed #bbb;
                             color: #666; }
)";

// Counts the plots whose SVG rendered (a non-empty box) with data (a series with points, or a
// frustum) and writes the count into the page; a check in a real browser reads it.
constexpr const char* kScript = R"(
(function () {
  var figures = document.querySelectorAll('figure.plot:not(.missing)');
  var rendered = 0;
  figures.forEach(function (f) {
    var svg = f.querySelector('svg');
    if (!svg) return;
    var box = svg.getBBox();
    var data = f.querySelectorAll("g.series:not([data-points='0']), g.frustum").length;
    if (box.width > 0 && box.height > 0 && data > 0) {
      rendered += 1;
      f.setAttribute('data-rendered', 'true');
    }
  });
  document.body.setAttribute('data-plots-rendered', String(rendered));
  document.body.setAttribute('data-plots-expected', String(figures.length));
  document.title = document.title + ' (' + rendered + '/' + figures.length + ' plots rendered)';
})();
)";

std::string Html(const std::string& text) { return plot::XmlEscape(text); }

std::string Number(double v, int digits) {
  return std::isfinite(v) ? SignificantText(v, digits) : "unknown";
}

std::string Vec(const Eigen::Vector3d& v, int decimals) { return Html(VectorText(v, decimals)); }

std::string QuaternionText(const Eigen::Quaterniond& q) {
  return fmt::format("({:.4f}, {:.4f}, {:.4f}, {:.4f})", q.w(), q.x(), q.y(), q.z());
}

std::string AxisAngleCell(const Eigen::Quaterniond& q) {
  const io::AxisAngleDegrees a = io::AxisAngleDeg(q);
  return FixedText(a.angle_deg, 3) + "° about " + VectorText(a.axis, 4);
}

void RenderFigure(const ReportFigure& f, std::ostringstream& out) {
  out << "<figure class=\"plot" << (f.svg.empty() ? " missing" : "") << "\" data-plot=\""
      << Html(f.name) << "\"";
  for (const auto& [name, value] : f.attributes) {
    out << " data-" << Html(name) << "=\"" << Html(value) << "\"";
  }
  out << ">\n<figcaption>" << Html(f.title) << "</figcaption>\n";
  if (!f.note.empty()) out << "<p class=\"note\">" << Html(f.note) << "</p>\n";
  if (f.svg.empty()) {
    out << "<div class=\"missing\">" << Html(f.missing) << "</div>\n";
  } else {
    out << f.svg;
  }
  out << "</figure>\n";
}

// The final table in the thesis's error-model columns (tab. 5.1): per slave the estimate and its
// σ, under it the truth when known; then the errors of 5.1.1 against the truth.
void RenderTable(const ReportData& data, std::ostringstream& out) {
  constexpr int kColumns = 10;
  out << "<div class=\"table\"><table class=\"final\">\n<tr><th>slave</th><th>state</th>"
         "<th>Δq (w, x, y, z)</th><th>rotation</th><th>ΔC ["
      << Html(data.distance_unit)
      << "]</th><th>‖ΔC‖</th><th>scale ± σ</th><th>σ rot [°]</th><th>σ C</th><th>motions used "
         "/ rejected</th></tr>\n";
  for (const SlaveCalibration& s : data.final_result.slaves) {
    const std::string state(ToString(s.state));
    const double scale_std = s.scales.empty() ? kUnknown : s.scales.back().std;
    out << "<tr class=\"estimate\"><td class=\"name\">" << Html(s.name)
        << "</td><td class=\"text state-" << state << "\">" << state << "</td><td>"
        << QuaternionText(s.estimate.q) << "</td><td class=\"rotation\">"
        << Html(AxisAngleCell(s.estimate.q)) << "</td><td>" << Vec(s.estimate.C, 4) << "</td><td>"
        << FixedText(s.estimate.C.norm(), 4) << "</td><td>" << Number(s.estimate.scale, 6) << " ± "
        << SigmaText(scale_std, 2) << "</td><td>" << SigmaText(s.rot_std_deg, 2) << "</td><td>"
        << SigmaVectorText(s.pos_std, 2) << "</td><td>" << s.motions.used << " / "
        << s.motions.rejected() << "</td></tr>\n";
    if (const auto t = data.truth.find(s.name); t != data.truth.end()) {
      const Similarity& g = t->second;
      out << "<tr class=\"truth\"><td class=\"name\">" << Html(s.name)
          << " truth</td><td class=\"text\">GT</td><td>" << QuaternionText(g.q)
          << "</td><td class=\"rotation\">" << Html(AxisAngleCell(g.q)) << "</td><td>"
          << Vec(g.C, 4) << "</td><td>" << FixedText(g.C.norm(), 4) << "</td><td>"
          << Number(g.scale, 6) << "</td><td colspan=\"" << kColumns - 7 << "\"></td></tr>\n";
    }
    if (!s.message.empty()) {
      out << "<tr><td></td><td class=\"message\" colspan=\"" << kColumns - 1 << "\">"
          << Html(s.message) << "</td></tr>\n";
    }
  }
  out << "</table></div>\n";
  if (data.truth.empty()) return;
  out << "<p class=\"source\">Errors against the truth (thesis 5.1.1):</p>\n"
      << "<div class=\"table\"><table class=\"final errors\">\n<tr><th>slave</th><th>rotation "
         "error [°]</th><th>position direction error [°]</th><th>distance error [%]</th>"
         "<th>|C − Ĉ| ["
      << Html(data.distance_unit) << "]</th><th>scale error [%]</th></tr>\n";
  for (const SlaveCalibration& s : data.final_result.slaves) {
    const auto t = data.truth.find(s.name);
    out << "<tr><td class=\"name\">" << Html(s.name) << "</td>";
    if (t == data.truth.end() || !s.usable()) {
      out << "<td colspan=\"5\" class=\"text\">" << (s.usable() ? "no truth" : "not usable")
          << "</td></tr>\n";
      continue;
    }
    io::SlaveScore score;  // scored as every truth comparison (io/truth_comparison.h)
    score.truth_master_units = t->second;
    io::ScoreSlave(s, &score);
    const CalibrationError& e = score.error;
    out << "<td>" << Number(e.rot_deg, 3) << "</td><td>" << Number(e.dir_deg, 3) << "</td><td>"
        << Number(e.dist_pct, 3) << "</td><td>" << Number(e.trans_err, 3) << "</td><td>"
        << (std::isfinite(e.scale_pct) ? Number(e.scale_pct, 3) : std::string("unknown slave unit"))
        << "</td></tr>\n";
  }
  out << "</table></div>\n";
}

}  // namespace

std::string RenderReportHtml(const ReportData& data) {
  using namespace internal;
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<title>rigcal report: " << Html(data.input) << "</title>\n<style>" << kStyle
      << "</style>\n</head>\n<body>\n";
  out << "<h1>rigcal report</h1>\n<p class=\"source\">" << Html(data.input) << " — "
      << (data.from_log ? std::to_string(data.extrinsics_messages) + " RIGCAL_EXTRINSICS, " +
                              std::to_string(data.status_messages) + " RIGCAL_STATUS messages"
                        : std::string("a result file"))
      << "; master " << Html(data.master) << ", distances in " << Html(data.distance_unit)
      << "</p>\n";
  if (!data.provenance.empty()) {
    out << "<ul class=\"provenance\">\n";
    for (const std::string& line : data.provenance) out << "<li>" << Html(line) << "</li>\n";
    out << "</ul>\n";
  }
  if (!data.notes.empty()) {
    out << "<ul class=\"notes\">\n";
    for (const std::string& note : data.notes) out << "<li>" << Html(note) << "</li>\n";
    out << "</ul>\n";
  }
  out << "<h2 id=\"final\">Final calibration</h2>\n";
  RenderTable(data, out);
  out << "<h2 id=\"baseline\">Baselines</h2>\n";
  RenderBaselineTable(data, out);
  out << "<h2 id=\"intrinsics\">Intrinsics</h2>\n";
  RenderIntrinsicsTable(data, out);
  out << "<h2 id=\"rig\">The rig</h2>\n";
  RenderFigure(RigViewFigure(data), out);
  out << "<h2 id=\"history\">Parameters over time</h2>\n";
  for (const ReportFigure& f : HistoryFigures(data)) RenderFigure(f, out);
  out << "<h2 id=\"motions\">Per motion: measured scales and constraint residua</h2>\n";
  if (data.motions) {
    out << "<p class=\"source\">motions of the " << Html(data.motions->pairs)
        << " pairs of the poses in " << Html(data.motions->source)
        << ", evaluated against the final estimate</p>\n";
  }
  for (const ReportFigure& f : MotionFigures(data)) RenderFigure(f, out);
  out << "<h2 id=\"health\">Camera health</h2>\n";
  RenderFigure(HealthFigure(data), out);
  out << "<script>" << kScript << "</script>\n</body>\n</html>\n";
  return out.str();
}

Status WriteReportHtml(const std::string& path, const ReportData& data) {
  return io::WriteFileAtomically(path, RenderReportHtml(data));
}

}  // namespace rigcal::report
