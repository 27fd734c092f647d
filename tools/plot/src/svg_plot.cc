// SPDX-License-Identifier: Apache-2.0
#include "rigcal/plot/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "rigcal/base/format.h"
#include "rigcal/io/atomic_file.h"

namespace rigcal::plot {
namespace {

// Colour-blind friendly palette (Okabe & Ito) plus black.
constexpr const char* kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                    "#E69F00", "#56B4E9", "#000000", "#F0E442"};
constexpr int kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);

// Panel margins around the plot area, pixels.
constexpr double kMarginLeft = 62;
constexpr double kMarginRight = 14;
constexpr double kMarginTop = 30;
constexpr double kMarginBottom = 46;
constexpr double kFigureTitleHeight = 28;
constexpr double kCharWidth = 6.2;  // approximate width of one 11px sans-serif character

// SVG coordinates: 2 decimals.
std::string Num(double v) { return FixedText(v, 2); }

// Tick label with as many decimals as the tick step needs.
std::string TickLabel(double v, double step) {
  int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  if (std::abs(v) < step * 1e-6) v = 0.0;  // no "-0.0"
  return FixedText(v, decimals);
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool valid() const { return lo <= hi; }
};

// Makes a degenerate or empty range plottable.
void Widen(Range* r) {
  if (!r->valid()) {
    r->lo = 0.0;
    r->hi = 1.0;
  } else if (r->hi - r->lo <= 1e-12 * std::max(1.0, std::abs(r->hi))) {
    double pad = std::abs(r->hi) > 0 ? 0.1 * std::abs(r->hi) : 1.0;
    r->lo -= pad;
    r->hi += pad;
  }
}

struct Axis {
  std::vector<double> ticks;
  double lo = 0;
  double hi = 1;
  double step = 1;
};

Axis MakeAxis(Range r, int tick_count = 6) {
  Widen(&r);
  Axis axis;
  axis.ticks = NiceTicks(r.lo, r.hi, tick_count);
  axis.lo = axis.ticks.front();
  axis.hi = axis.ticks.back();
  axis.step = axis.ticks.size() > 1 ? axis.ticks[1] - axis.ticks[0] : 1.0;
  return axis;
}

std::string SeriesColor(const PlotSeries& s, size_t index) {
  return s.color.empty() ? kPalette[index % kPaletteSize] : s.color;
}

// The stroke-dasharray attribute of a series' line ("" for a solid one).
std::string DashAttribute(const PlotSeries& s) {
  if (!s.dash_array.empty()) return " stroke-dasharray=\"" + XmlEscape(s.dash_array) + "\"";
  return s.dashed ? " stroke-dasharray=\"6 4\"" : "";
}

// One marker of shape `marker` centred at (x, y) with radius r (pixels).
std::string MarkerElement(Marker marker, double x, double y, double r, const std::string& color) {
  const auto point = [](double px, double py) { return Num(px) + "," + Num(py) + " "; };
  switch (marker) {
    case Marker::kSquare:
      return "<rect x=\"" + Num(x - r) + "\" y=\"" + Num(y - r) + "\" width=\"" + Num(2 * r) +
             "\" height=\"" + Num(2 * r) + "\" fill=\"" + color + "\"/>\n";
    case Marker::kTriangle:
      return "<polygon points=\"" + point(x, y - 1.2 * r) + point(x - 1.1 * r, y + 0.8 * r) +
             point(x + 1.1 * r, y + 0.8 * r) + "\" fill=\"" + color + "\"/>\n";
    case Marker::kDiamond:
      return "<polygon points=\"" + point(x, y - 1.3 * r) + point(x + 1.3 * r, y) +
             point(x, y + 1.3 * r) + point(x - 1.3 * r, y) + "\" fill=\"" + color + "\"/>\n";
    case Marker::kCross:
      return "<path d=\"M" + Num(x - r) + "," + Num(y - r) + "L" + Num(x + r) + "," + Num(y + r) +
             "M" + Num(x - r) + "," + Num(y + r) + "L" + Num(x + r) + "," + Num(y - r) +
             "\" stroke=\"" + color + "\" stroke-width=\"1.4\" fill=\"none\"/>\n";
    case Marker::kCircle:
      break;
  }
  return "<circle cx=\"" + Num(x) + "\" cy=\"" + Num(y) + "\" r=\"" + Num(r) + "\" fill=\"" +
         color + "\"/>\n";
}

bool HasBand(const PlotSeries& s) {
  return !s.band_lo.empty() && s.band_lo.size() == s.x.size() && s.band_hi.size() == s.x.size();
}

// The band of `s` as filled polygons, one per run of finite bounds.
template <typename ToX, typename ToY>
void RenderBand(const PlotSeries& s, const std::string& color, ToX px, ToY py,
                std::ostringstream& out) {
  size_t i = 0;
  const size_t n = s.x.size();
  auto finite = [&](size_t k) {
    return std::isfinite(s.x[k]) && std::isfinite(s.band_lo[k]) && std::isfinite(s.band_hi[k]);
  };
  while (i < n) {
    while (i < n && !finite(i)) ++i;
    size_t end = i;
    while (end < n && finite(end)) ++end;
    if (end > i) {
      std::string points;
      for (size_t k = i; k < end; ++k) {
        points += Num(px(s.x[k])) + "," + Num(py(s.band_hi[k])) + " ";
      }
      for (size_t k = end; k-- > i;) {
        points += Num(px(s.x[k])) + "," + Num(py(s.band_lo[k])) + " ";
      }
      points.pop_back();
      out << "<polygon class=\"band\" fill=\"" << color
          << "\" fill-opacity=\"0.18\" stroke=\"none\" points=\"" << points << "\"/>\n";
    }
    i = end;
  }
}

// The x and y ranges of the panel's data, bands and reference lines (the y range as the panel
// asks: from zero, or fixed).
void PanelRanges(const PlotPanel& panel, Range* xr, Range* yr) {
  for (const PlotSeries& s : panel.series) {
    size_t n = std::min(s.x.size(), s.y.size());
    for (size_t i = 0; i < n; ++i) {
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        xr->Add(s.x[i]);
        yr->Add(s.y[i]);
      }
    }
    if (HasBand(s)) {
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (!std::isfinite(s.x[i])) continue;
        yr->Add(s.band_lo[i]);
        yr->Add(s.band_hi[i]);
      }
    }
  }
  for (const ReferenceLine& line : panel.reference_lines) yr->Add(line.y);
  if (panel.y_from_zero) yr->Add(0.0);
  if (std::isfinite(panel.y_min) && std::isfinite(panel.y_max) && panel.y_min < panel.y_max) {
    *yr = Range{panel.y_min, panel.y_max};
  }
}

// The legend's entries (those with a label) and its size in pixels.
struct LegendSize {
  int entries = 0;
  double width = 0.0;
  double height = 0.0;
};

LegendSize MeasureLegend(const PlotPanel& panel) {
  size_t longest = 0;
  LegendSize size;
  for (const PlotSeries& s : panel.series) {
    if (s.label.empty()) continue;
    longest = std::max(longest, s.label.size());
    ++size.entries;
  }
  for (const ReferenceLine& line : panel.reference_lines) {
    if (line.label.empty()) continue;
    longest = std::max(longest, line.label.size());
    ++size.entries;
  }
  size.width = 34 + kCharWidth * static_cast<double>(longest);
  size.height = 6 + 14.0 * size.entries;
  return size;
}

// The plot area of a panel in SVG pixels and its axes: data (x, y) to pixels.
struct PanelFrame {
  double left = 0.0;
  double top = 0.0;
  double pw = 0.0;  // width of the plot area
  double ph = 0.0;  // height
  Axis xa;
  Axis ya;
  double X(double x) const { return left + (x - xa.lo) / (xa.hi - xa.lo) * pw; }
  double Y(double y) const { return top + ph - (y - ya.lo) / (ya.hi - ya.lo) * ph; }
};

// The frame, grid, tick labels, axis labels and title.
void RenderAxes(const PlotPanel& panel, const PanelFrame& f, double x0, double y0,
                std::ostringstream& out) {
  out << "<rect x=\"" << Num(f.left) << "\" y=\"" << Num(f.top) << "\" width=\"" << Num(f.pw)
      << "\" height=\"" << Num(f.ph) << "\" fill=\"#ffffff\" stroke=\"#333333\"/>\n";
  for (double t : f.xa.ticks) {
    double x = f.X(t);
    out << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(f.top) << "\" x2=\"" << Num(x) << "\" y2=\""
        << Num(f.top + f.ph) << "\" stroke=\"#e5e5e5\"/>\n";
    out << "<text x=\"" << Num(x) << "\" y=\"" << Num(f.top + f.ph + 15)
        << "\" text-anchor=\"middle\">" << XmlEscape(TickLabel(t, f.xa.step)) << "</text>\n";
  }
  for (double t : f.ya.ticks) {
    double y = f.Y(t);
    out << "<line x1=\"" << Num(f.left) << "\" y1=\"" << Num(y) << "\" x2=\"" << Num(f.left + f.pw)
        << "\" y2=\"" << Num(y) << "\" stroke=\"#e5e5e5\"/>\n";
    out << "<text x=\"" << Num(f.left - 5) << "\" y=\"" << Num(y + 4) << "\" text-anchor=\"end\">"
        << XmlEscape(TickLabel(t, f.ya.step)) << "</text>\n";
  }
  out << "<text x=\"" << Num(f.left + f.pw / 2) << "\" y=\"" << Num(f.top + f.ph + 36)
      << "\" text-anchor=\"middle\">" << XmlEscape(panel.x_label) << "</text>\n";
  double ly = f.top + f.ph / 2;
  double lx = x0 + 14;
  out << "<text x=\"" << Num(lx) << "\" y=\"" << Num(ly) << "\" text-anchor=\"middle\" "
      << "transform=\"rotate(-90 " << Num(lx) << " " << Num(ly) << ")\">"
      << XmlEscape(panel.y_label) << "</text>\n";
  out << "<text x=\"" << Num(f.left + f.pw / 2) << "\" y=\"" << Num(y0 + 19)
      << "\" text-anchor=\"middle\" font-weight=\"bold\">" << XmlEscape(panel.title) << "</text>\n";
}

// One series (its band, polylines broken at non-finite points, markers), clipped to the plot.
void RenderSeries(const PlotSeries& s, size_t si, const PanelFrame& f, const std::string& clip_id,
                  std::ostringstream& out) {
  const std::string color = SeriesColor(s, si);
  const auto px = [&f](double x) { return f.X(x); };
  const auto py = [&f](double y) { return f.Y(y); };
  size_t n = std::min(s.x.size(), s.y.size());
  int finite_points = 0;
  for (size_t i = 0; i < n; ++i) finite_points += std::isfinite(s.x[i]) && std::isfinite(s.y[i]);
  out << "<g class=\"series\" data-label=\"" << XmlEscape(s.label) << "\" data-points=\""
      << finite_points << "\" clip-path=\"url(#" << clip_id << ")\">\n";
  if (HasBand(s)) RenderBand(s, color, px, py, out);
  std::string points;
  auto flush = [&]() {
    if (!points.empty() && s.lines) {
      out << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"1.6\""
          << DashAttribute(s) << " points=\"" << points << "\"/>\n";
    }
    points.clear();
  };
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
      flush();
      continue;
    }
    if (!points.empty()) points += ' ';
    points += Num(px(s.x[i])) + "," + Num(py(s.y[i]));
  }
  flush();
  if (s.markers) {
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      out << MarkerElement(s.marker, px(s.x[i]), py(s.y[i]), 2.2, color);
    }
  }
  out << "</g>\n";
}

void RenderReferenceLines(const PlotPanel& panel, const PanelFrame& f, std::ostringstream& out) {
  for (const ReferenceLine& line : panel.reference_lines) {
    if (!std::isfinite(line.y) || line.y < f.ya.lo || line.y > f.ya.hi) continue;
    out << "<line class=\"reference\" x1=\"" << Num(f.left) << "\" y1=\"" << Num(f.Y(line.y))
        << "\" x2=\"" << Num(f.left + f.pw) << "\" y2=\"" << Num(f.Y(line.y)) << "\" stroke=\""
        << (line.color.empty() ? "#666666" : line.color) << "\" stroke-width=\"1.2\""
        << (line.dashed ? " stroke-dasharray=\"6 4\"" : "") << "/>\n";
  }
}

// The legend box: a line or marker and the label of every labelled series and reference line.
void RenderLegend(const PlotPanel& panel, const PanelFrame& f, const LegendSize& legend,
                  bool outside, std::ostringstream& out) {
  double bx = f.left + 6;
  if (panel.legend == LegendPosition::kTopRight) bx = f.left + f.pw - 6 - legend.width;
  if (outside) bx = f.left + f.pw + 8;
  const double by = outside ? f.top : f.top + 6;
  out << "<g class=\"legend\">\n<rect x=\"" << Num(bx) << "\" y=\"" << Num(by) << "\" width=\""
      << Num(legend.width) << "\" height=\"" << Num(legend.height)
      << "\" fill=\"#ffffff\" fill-opacity=\"0.85\" stroke=\"#999999\"/>\n";
  int row = 0;
  for (size_t si = 0; si < panel.series.size(); ++si) {
    const PlotSeries& s = panel.series[si];
    if (s.label.empty()) continue;
    double ey = by + 11 + 14.0 * row++;
    if (s.lines) {
      out << "<line x1=\"" << Num(bx + 5) << "\" y1=\"" << Num(ey - 3) << "\" x2=\"" << Num(bx + 27)
          << "\" y2=\"" << Num(ey - 3) << "\" stroke=\"" << SeriesColor(s, si)
          << "\" stroke-width=\"1.6\"" << DashAttribute(s) << "/>\n";
    }
    if (s.markers || !s.lines)
      out << MarkerElement(s.marker, bx + 16, ey - 3, 2.6, SeriesColor(s, si));
    out << "<text x=\"" << Num(bx + 31) << "\" y=\"" << Num(ey) << "\">" << XmlEscape(s.label)
        << "</text>\n";
  }
  for (const ReferenceLine& line : panel.reference_lines) {
    if (line.label.empty()) continue;
    double ey = by + 11 + 14.0 * row++;
    out << "<line x1=\"" << Num(bx + 5) << "\" y1=\"" << Num(ey - 3) << "\" x2=\"" << Num(bx + 27)
        << "\" y2=\"" << Num(ey - 3) << "\" stroke=\""
        << (line.color.empty() ? "#666666" : line.color) << "\" stroke-width=\"1.2\""
        << (line.dashed ? " stroke-dasharray=\"6 4\"" : "") << "/>\n";
    out << "<text x=\"" << Num(bx + 31) << "\" y=\"" << Num(ey) << "\">" << XmlEscape(line.label)
        << "</text>\n";
  }
  out << "</g>\n";
}

void RenderPanel(const PlotPanel& panel, const std::string& id, double x0, double y0, double width,
                 double height, std::ostringstream& out) {
  Range xr;
  Range yr;
  PanelRanges(panel, &xr, &yr);
  PanelFrame f;
  f.xa = MakeAxis(xr);
  f.ya = MakeAxis(yr, panel.y_tick_count);
  const LegendSize legend = MeasureLegend(panel);
  const bool outside = panel.legend == LegendPosition::kOutsideRight && legend.entries > 0;
  f.left = x0 + kMarginLeft;
  f.top = y0 + kMarginTop;
  f.pw = std::max(40.0, width - kMarginLeft - kMarginRight - (outside ? legend.width + 8 : 0.0));
  f.ph = height - kMarginTop - kMarginBottom;

  out << "<g class=\"panel\">\n";
  RenderAxes(panel, f, x0, y0, out);
  // Series, clipped to the plot area.
  const std::string clip_id = id;
  out << "<clipPath id=\"" << clip_id << "\"><rect x=\"" << Num(f.left) << "\" y=\"" << Num(f.top)
      << "\" width=\"" << Num(f.pw) << "\" height=\"" << Num(f.ph) << "\"/></clipPath>\n";
  for (size_t si = 0; si < panel.series.size(); ++si) {
    RenderSeries(panel.series[si], si, f, clip_id, out);
  }
  RenderReferenceLines(panel, f, out);
  if (legend.entries > 0) RenderLegend(panel, f, legend, outside, out);
  out << "</g>\n";
}

}  // namespace

std::string XmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::vector<double> NiceTicks(double lo, double hi, int target_count) {
  target_count = std::max(2, target_count);
  double raw = (hi - lo) / (target_count - 1);
  double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw * (1 - 1e-9)) break;
  }
  double first = std::floor(lo / step + 1e-9) * step;
  double last = std::ceil(hi / step - 1e-9) * step;
  std::vector<double> ticks;
  int count = static_cast<int>(std::llround((last - first) / step)) + 1;
  for (int i = 0; i < count; ++i) ticks.push_back(first + i * step);
  if (ticks.size() < 2) ticks.push_back(first + step);
  return ticks;
}

std::string RenderSvg(const PlotFigure& figure) {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + RenderSvgElement(figure);
}

std::string RenderSvgElement(const PlotFigure& figure) {
  const int n = static_cast<int>(figure.panels.size());
  const int columns =
      figure.columns > 0 ? std::min(figure.columns, std::max(n, 1)) : std::max(n, 1);
  const int rows = std::max(1, (n + columns - 1) / columns);
  const double title_h = figure.title.empty() ? 0.0 : kFigureTitleHeight;
  const double width = static_cast<double>(columns) * figure.panel_width;
  const double height = title_h + static_cast<double>(rows) * figure.panel_height;

  std::ostringstream out;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << Num(width)
      << "\" height=\"" << Num(height) << "\" viewBox=\"0 0 " << Num(width) << " " << Num(height)
      << "\" font-family=\"DejaVu Sans, Arial, Helvetica, sans-serif\" font-size=\"11\">\n";
  out << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  if (!figure.title.empty()) {
    out << "<text x=\"" << Num(width / 2) << "\" y=\"19\" text-anchor=\"middle\" "
        << "font-size=\"14\" font-weight=\"bold\">" << XmlEscape(figure.title) << "</text>\n";
  }
  for (int i = 0; i < n; ++i) {
    double x0 = static_cast<double>(i % columns) * figure.panel_width;
    double y0 = title_h + static_cast<double>(i / columns) * figure.panel_height;
    RenderPanel(figure.panels[i], figure.id_prefix + "clip" + std::to_string(i), x0, y0,
                figure.panel_width, figure.panel_height, out);
  }
  out << "</svg>\n";
  return out.str();
}

Status WriteSvg(const PlotFigure& figure, const std::string& path) {
  return io::WriteFileAtomically(path, RenderSvg(figure));
}

}  // namespace rigcal::plot
