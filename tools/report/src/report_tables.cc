// SPDX-License-Identifier: Apache-2.0
#include "report_tables.h"

#include <cmath>
#include <string>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/plot/svg_plot.h"

namespace rigcal::report::internal {
namespace {

std::string Html(const std::string& text) { return plot::XmlEscape(text); }

// Numbers of the intrinsics with the precision they are written with (shortest round trip).
std::string Numbers(const std::vector<double>& values) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : " ") + ShortestText(v);
  return out.empty() ? "none" : out;
}

std::string DistortionName(const camera::CameraSpec& spec) {
  switch (spec.model) {
    case camera::CameraSpec::Model::kPinhole:
      return "radtan";
    case camera::CameraSpec::Model::kFisheye:
      return "equidistant";
    case camera::CameraSpec::Model::kScaramuzza:
      return "polynomial";
  }
  return "";
}

}  // namespace

Baseline BaselineOf(const Eigen::Vector3d& C, const Eigen::Vector3d& C_std) {
  Baseline b;
  b.norm = C.norm();
  if (b.norm <= 0.0 || !C_std.allFinite()) return b;
  b.std = C.cwiseProduct(C_std).norm() / b.norm;
  return b;
}

void RenderBaselineTable(const ReportData& data, std::ostringstream& out) {
  const bool metric = std::isfinite(data.metres_per_unit);
  out << "<div class=\"table\"><table class=\"final baseline\">\n<tr><th>slave</th><th>|C| ± σ ["
      << Html(data.distance_unit) << "]</th>"
      << (metric ? "<th>baseline |C| ± σ [m]</th><th>metres from</th>" : "") << "</tr>\n";
  for (const SlaveCalibration& s : data.final_result.slaves) {
    const Baseline b = BaselineOf(s.estimate.C, s.pos_std);
    out << "<tr data-slave=\"" << Html(s.name) << "\"><td class=\"name\">" << Html(s.name)
        << "</td>";
    if (!s.usable()) {
      out << "<td class=\"text\" colspan=\"" << (metric ? 3 : 1) << "\">not usable</td></tr>\n";
      continue;
    }
    out << "<td class=\"unit\">" << FixedText(b.norm, 4) << " ± " << SigmaText(b.std, 2) << "</td>";
    if (metric) {
      out << "<td class=\"metres\">" << FixedText(b.norm * data.metres_per_unit, 4) << " ± "
          << SigmaText(b.std * data.metres_per_unit, 2) << "</td><td class=\"text\">"
          << Html(data.metres_source) << "</td>";
    }
    out << "</tr>\n";
  }
  out << "</table></div>\n";
  if (!metric) {
    out << "<p class=\"source unit\">C is in " << Html(data.distance_unit)
        << " (the master odometry's unit), not metres: a metric master (`metric: true` in "
           "--config), a target reference or --metric-* of solve, or a metric truth gives "
           "the baseline in metres.</p>\n";
  }
}

void RenderIntrinsicsTable(const ReportData& data, std::ostringstream& out) {
  if (data.intrinsics.empty()) {
    out << "<p class=\"source\">"
        << (data.config.empty() ? "no rig config given (--config): no intrinsics"
                                : "no camera of " + Html(data.config) + " has intrinsics")
        << "</p>\n";
    return;
  }
  out << "<p class=\"source\">from " << Html(data.config) << "</p>\n"
      << "<div class=\"table\"><table class=\"final intrinsics\">\n<tr><th>camera</th><th>model"
         "</th><th>fx fy cx cy [px]</th><th>distortion</th><th>coefficients</th><th>resolution "
         "[px]</th></tr>\n";
  for (const camera::CameraSpec& spec : data.intrinsics) {
    const bool scaramuzza = spec.model == camera::CameraSpec::Model::kScaramuzza;
    const std::vector<double> projection =
        scaramuzza ? std::vector<double>{spec.center[0], spec.center[1]}
                   : std::vector<double>(spec.intrinsics.begin(), spec.intrinsics.end());
    out << "<tr data-camera=\"" << Html(spec.name) << "\"><td class=\"name\">" << Html(spec.name)
        << "</td><td class=\"text model\">" << camera::ModelName(spec.model)
        << "</td><td class=\"projection\">" << (scaramuzza ? "centre " : "") << Numbers(projection)
        << "</td><td class=\"text\">" << DistortionName(spec) << "</td><td class=\"distortion\">"
        << Numbers(scaramuzza ? spec.poly : spec.distortion) << "</td><td class=\"resolution\">"
        << spec.width << " × " << spec.height << "</td></tr>\n";
  }
  out << "</table></div>\n";
}

}  // namespace rigcal::report::internal
