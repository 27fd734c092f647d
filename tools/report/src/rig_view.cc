// SPDX-License-Identifier: Apache-2.0
// The rig drawn from the top and from the side: every camera as a frustum (the master at the
// origin), the truth dashed.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "report_plots.h"
#include "rigcal/base/format.h"
#include "rigcal/plot/svg_plot.h"

namespace rigcal::report::internal {
namespace {

constexpr double kPanelSize = 420;
constexpr double kMargin = 40;
constexpr double kHalfFov = 0.55;  // tan of the drawn half field of view (~29 deg)

struct Camera {
  std::string name;
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // master_from_camera
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  std::string color;
  bool dashed = false;
};

// The frustum's apex and four far corners in the master frame.
std::vector<Eigen::Vector3d> Frustum(const Camera& camera, double depth) {
  std::vector<Eigen::Vector3d> points = {camera.C};
  for (const auto& [u, v] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
    points.push_back(camera.C +
                     camera.q * Eigen::Vector3d(u * kHalfFov, v * kHalfFov, 1.0) * depth);
  }
  return points;
}

struct View {
  std::string title;
  int horizontal;  // master axis drawn to the right
  int vertical;    // master axis drawn upwards
  double sign_up;  // +1, or -1 when the axis points down (y of a camera frame)
  std::string h_label;
  std::string v_label;
};

void RenderView(const View& view, const std::vector<Camera>& cameras, double depth, double x0,
                std::ostringstream& out) {
  double lo_h = 1e300, hi_h = -1e300, lo_v = 1e300, hi_v = -1e300;
  for (const Camera& c : cameras) {
    for (const Eigen::Vector3d& p : Frustum(c, depth)) {
      lo_h = std::min(lo_h, p[view.horizontal]);
      hi_h = std::max(hi_h, p[view.horizontal]);
      lo_v = std::min(lo_v, view.sign_up * p[view.vertical]);
      hi_v = std::max(hi_v, view.sign_up * p[view.vertical]);
    }
  }
  const double span = std::max({hi_h - lo_h, hi_v - lo_v, 1e-9}) * 1.15;
  const double mid_h = 0.5 * (lo_h + hi_h), mid_v = 0.5 * (lo_v + hi_v);
  const double scale = (kPanelSize - 2 * kMargin) / span;
  auto px = [&](const Eigen::Vector3d& p) {
    return x0 + kPanelSize / 2 + (p[view.horizontal] - mid_h) * scale;
  };
  auto py = [&](const Eigen::Vector3d& p) {
    return kPanelSize / 2 + 10 - (view.sign_up * p[view.vertical] - mid_v) * scale;
  };
  auto num = [](double v) { return FixedText(v, 2); };
  out << "<g class=\"panel rig-view\">\n";
  out << "<rect x=\"" << num(x0 + 4) << "\" y=\"24\" width=\"" << num(kPanelSize - 8)
      << "\" height=\"" << num(kPanelSize - 12) << "\" fill=\"#ffffff\" stroke=\"#333333\"/>\n";
  out << "<text x=\"" << num(x0 + kPanelSize / 2) << "\" y=\"17\" text-anchor=\"middle\" "
      << "font-weight=\"bold\">" << plot::XmlEscape(view.title) << "</text>\n";
  // The view's axes as a glyph in the lower left corner.
  const double gx = x0 + 22, gy = kPanelSize - 8;
  out << "<g class=\"axes\" stroke=\"#999999\"><line x1=\"" << num(gx) << "\" y1=\"" << num(gy)
      << "\" x2=\"" << num(gx + 30) << "\" y2=\"" << num(gy) << "\"/><line x1=\"" << num(gx)
      << "\" y1=\"" << num(gy) << "\" x2=\"" << num(gx) << "\" y2=\"" << num(gy - 30)
      << "\"/></g>\n";
  out << "<text x=\"" << num(gx + 34) << "\" y=\"" << num(gy + 4) << "\" fill=\"#777777\">"
      << plot::XmlEscape(view.h_label) << "</text>\n";
  out << "<text x=\"" << num(gx - 4) << "\" y=\"" << num(gy - 34) << "\" fill=\"#777777\">"
      << plot::XmlEscape(view.v_label) << "</text>\n";
  for (const Camera& c : cameras) {
    const std::vector<Eigen::Vector3d> f = Frustum(c, depth);
    out << "<g class=\"frustum\" data-camera=\"" << plot::XmlEscape(c.name) << "\" stroke=\"" << c.color
        << "\" fill=\"none\" stroke-width=\"1.5\"" << (c.dashed ? " stroke-dasharray=\"5 3\"" : "")
        << ">\n";
    std::string corners;
    for (int k = 1; k <= 4; ++k) {
      out << "<line x1=\"" << num(px(f[0])) << "\" y1=\"" << num(py(f[0])) << "\" x2=\""
          << num(px(f[k])) << "\" y2=\"" << num(py(f[k])) << "\"/>\n";
      corners += num(px(f[k])) + "," + num(py(f[k])) + " ";
    }
    corners.pop_back();
    out << "<polygon points=\"" << corners << "\" fill=\"" << c.color
        << "\" fill-opacity=\"0.08\"/>\n";
    out << "<circle cx=\"" << num(px(f[0])) << "\" cy=\"" << num(py(f[0])) << "\" r=\"3\" fill=\""
        << c.color << "\"/>\n";
    if (!c.dashed) {
      out << "<text x=\"" << num(px(f[0]) + 6) << "\" y=\"" << num(py(f[0]) + 14)
          << "\" stroke=\"none\" fill=\"" << c.color << "\">" << plot::XmlEscape(c.name) << "</text>\n";
    }
    out << "</g>\n";
  }
  out << "</g>\n";
}

}  // namespace

ReportFigure RigViewFigure(const ReportData& data) {
  constexpr const char* kColors[] = {"#000000", "#0072B2", "#D55E00", "#009E73",
                                     "#CC79A7", "#E69F00", "#56B4E9"};
  std::vector<Camera> cameras;
  cameras.push_back({data.master + " (master)", Eigen::Quaterniond::Identity(),
                     Eigen::Vector3d::Zero(), kColors[0], false});
  double extent = 0.0;
  int index = 1;
  for (const SlaveCalibration& s : data.final_result.slaves) {
    const std::string color = kColors[index++ % 7];
    if (const auto t = data.truth.find(s.name); t != data.truth.end()) {
      cameras.push_back({s.name + " truth", t->second.q, t->second.C, "#999999", true});
      extent = std::max(extent, t->second.C.norm());
    }
    if (!s.solved() && !s.usable()) continue;  // placeholders of an initialising slave
    cameras.push_back({s.name, s.estimate.q, s.estimate.C, color, false});
    extent = std::max(extent, s.estimate.C.norm());
  }
  const double depth = extent > 0.0 ? 0.3 * extent : 1.0;
  std::ostringstream out;
  const double width = 2 * kPanelSize;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << width
      << "\" height=\"" << kPanelSize + 20 << "\" viewBox=\"0 0 " << width << " " << kPanelSize + 20
      << "\" font-family=\"DejaVu Sans, Arial, Helvetica, sans-serif\" "
      << "font-size=\"11\">\n";
  // Master camera frame: x right, y down, z forward (the optical axis).
  RenderView({"top view (looking down along -y)", 0, 2, 1.0, "x", "z (forward)"}, cameras, depth, 0,
             out);
  RenderView({"side view (looking along x)", 2, 1, -1.0, "z (forward)", "-y (up)"}, cameras, depth,
             kPanelSize, out);
  out << "</svg>\n";
  ReportFigure figure;
  figure.name = "rig-view";
  figure.title = "the rig: final estimate, master frame";
  figure.note = "frusta " + SignificantText(depth, 3) + " " + data.distance_unit +
                " deep; grey dashed: the truth; an initialising slave is not drawn";
  figure.svg = out.str();
  return figure;
}

}  // namespace rigcal::report::internal
