// SPDX-License-Identifier: Apache-2.0
// The per-motion residua of every slave as histograms (issue 37 §7), beside the residua over
// time (thesis fig. 5.11).
#include "residual_histograms.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "report_plots.h"
#include "rigcal/base/format.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/plot/svg_plot.h"

namespace rigcal::report::internal {
namespace {

constexpr int kMinBins = 5;
constexpr int kMaxBins = 25;

// `text` usable in element ids (plot::PlotFigure::id_prefix).
std::string IdSafe(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
  return out;
}

std::string Joined(const std::vector<double>& values) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : " ") + ShortestText(v);
  return out;
}

std::string Joined(const std::vector<int>& values) {
  std::string out;
  for (int v : values) out += (out.empty() ? "" : " ") + std::to_string(v);
  return out;
}

// The histogram as a filled outline (a step line from 0 to 0 with the counts as a band) and its
// σ as a dashed vertical line.
plot::PlotPanel HistogramPanel(const std::string& title, const std::string& x_label,
                               const Histogram& h, const std::string& unit) {
  plot::PlotPanel panel;
  panel.title = title;
  panel.x_label = x_label;
  panel.y_label = "motions per bin";
  panel.legend = plot::LegendPosition::kTopRight;
  plot::PlotSeries bars;
  bars.label = std::to_string(h.values) + " motions";
  bars.color = "#0072B2";
  bars.markers = false;
  auto add = [&bars](double x, double y) {
    bars.x.push_back(x);
    bars.y.push_back(y);
    bars.band_lo.push_back(0.0);
    bars.band_hi.push_back(y);
  };
  add(h.edges.front(), 0.0);
  for (size_t b = 0; b < h.counts.size(); ++b) {
    add(h.edges[b], h.counts[b]);
    add(h.edges[b + 1], h.counts[b]);
  }
  add(h.edges.back(), 0.0);
  plot::PlotSeries sigma;
  sigma.label = "σ (RMS) " + SignificantText(h.rms, 3) + " " + unit;
  sigma.color = "#D55E00";
  sigma.dash_array = "6 3";
  sigma.markers = false;
  const int highest = h.counts.empty() ? 1 : *std::max_element(h.counts.begin(), h.counts.end());
  sigma.x = {h.rms, h.rms};
  sigma.y = {0.0, static_cast<double>(highest)};
  panel.series = {bars, sigma};
  return panel;
}

}  // namespace

Histogram HistogramOf(const std::vector<double>& values) {
  Histogram h;
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(std::abs(v));
  }
  h.values = static_cast<int>(finite.size());
  const double largest = finite.empty() ? 0.0 : *std::max_element(finite.begin(), finite.end());
  const int bins =
      std::clamp(static_cast<int>(std::lround(std::sqrt(h.values))), kMinBins, kMaxBins);
  h.edges = plot::NiceTicks(0.0, largest > 0.0 ? largest : 1.0, bins + 1);
  h.counts.assign(h.edges.size() - 1, 0);
  const double width = h.edges[1] - h.edges[0];
  double squares = 0.0;
  for (double v : finite) {
    const auto b = static_cast<size_t>(std::floor(v / width));
    ++h.counts[std::min(b, h.counts.size() - 1)];
    squares += v * v;
  }
  if (h.values > 0) {
    h.rms = std::sqrt(squares / h.values);
    h.median = UpperMedian(finite);
  }
  return h;
}

ReportFigure HistogramFigure(const std::string& slave, const SlaveMotions& motions,
                             const std::string& distance_unit) {
  std::vector<double> rotation, position;
  for (const MotionSample& m : motions.samples) {
    rotation.push_back(m.rotation_deg);
    position.push_back(m.position_abs);
  }
  const Histogram r = HistogramOf(rotation);
  const Histogram p = HistogramOf(position);
  plot::PlotFigure figure;
  figure.id_prefix = "histograms-" + IdSafe(slave) + "-";
  figure.columns = 2;
  figure.panel_width = 560;
  figure.panel_height = 280;
  figure.panels = {HistogramPanel("rotation constraint residuum", "angle [deg]", r, "deg"),
                   HistogramPanel("position constraint residuum",
                                  "|residual| [" + distance_unit + "]", p, distance_unit)};
  ReportFigure f;
  f.name = "histograms-" + slave;
  f.title = slave + ": residua per motion (histograms)";
  f.note = std::to_string(r.values) + " motions against the final estimate; rotation σ (RMS) " +
           SignificantText(r.rms, 3) + " deg, median " + SignificantText(r.median, 3) +
           " deg; position σ (RMS) " + SignificantText(p.rms, 3) + " " + distance_unit +
           ", median " + SignificantText(p.median, 3) + " " + distance_unit;
  f.svg = plot::RenderSvgElement(figure);
  f.attributes = {
      {"residuals", std::to_string(r.values)}, {"rotation-edges-deg", Joined(r.edges)},
      {"rotation-counts", Joined(r.counts)},   {"rotation-sigma-deg", ShortestText(r.rms)},
      {"position-edges", Joined(p.edges)},     {"position-counts", Joined(p.counts)},
      {"position-sigma", ShortestText(p.rms)}};
  return f;
}

}  // namespace rigcal::report::internal
