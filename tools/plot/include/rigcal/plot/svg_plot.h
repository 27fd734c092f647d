// SPDX-License-Identifier: Apache-2.0
#pragma once
// A small standalone SVG line-plot writer for the experiment figures and the HTML report: one or
// more panels, each with axes, "nice" ticks, axis labels, a title, a legend, any number of line
// or scatter series with optional ±σ bands, and horizontal reference lines (a truth, a
// threshold). No external library; the output is a valid standalone SVG 1.1 document with
// XML-escaped text, or the bare <svg> element to inline into HTML.

#include <limits>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::plot {

// The shape drawn at every point of a series with markers (and in its legend entry).
enum class Marker { kCircle, kSquare, kTriangle, kDiamond, kCross };

struct PlotSeries {
  std::string label;      // legend text (empty: not in the legend)
  std::vector<double> x;  // same length as y
  std::vector<double> y;  // a non-finite value breaks the line into separate pieces
  std::string color;      // CSS colour; empty = the palette colour of the series index
  bool dashed = false;
  bool markers = true;  // a small marker (`marker`) at every finite point
  bool lines = true;    // false: markers only (a scatter plot)
  // Optional band around the series (e.g. ±σ), drawn filled in the series colour below it:
  // empty, or the same length as x. A non-finite bound breaks the band.
  std::vector<double> band_lo = {};
  std::vector<double> band_hi = {};
  Marker marker = Marker::kCircle;
  // SVG stroke-dasharray of the line (e.g. "2 3"): overrides `dashed` when not empty.
  std::string dash_array = {};
};

// A horizontal line across the plot area at y (a truth value, a threshold), in the y range.
struct ReferenceLine {
  double y = 0.0;
  std::string label;  // legend text (empty: not in the legend)
  std::string color;  // CSS colour; empty = grey
  bool dashed = true;
};

enum class LegendPosition {
  kTopLeft,       // inside the plot area
  kTopRight,      // inside the plot area
  kOutsideRight,  // right of the plot area (which gets narrower), never covers data
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  std::vector<ReferenceLine> reference_lines;
  bool y_from_zero = true;  // the y range always includes 0 (error plots)
  // A fixed y range when both are finite (y_min < y_max): points outside it are clipped.
  double y_min = std::numeric_limits<double>::quiet_NaN();
  double y_max = std::numeric_limits<double>::quiet_NaN();
  int y_tick_count = 6;  // about this many y ticks (>= 2)
  LegendPosition legend = LegendPosition::kTopLeft;
};

struct PlotFigure {
  std::string title;              // above all panels (may be empty)
  std::vector<PlotPanel> panels;  // laid out left to right, top to bottom
  int columns = 0;                // panels per row; 0 = all panels in one row
  int panel_width = 400;          // pixels, including the panel's axis margins
  int panel_height = 320;
  // Prefix of the element ids (clip paths) of this figure: figures inlined into one HTML
  // document need distinct prefixes. Letters, digits, '-' and '_' only.
  std::string id_prefix;
};

// The figure as an SVG document. Every series is drawn as one <g class="series"> element (also
// when it has no finite point), so a reader can count the series of a figure. Thread-safe.
std::string RenderSvg(const PlotFigure& figure);

// The same figure as a bare <svg> element (no XML declaration), to inline into HTML.
std::string RenderSvgElement(const PlotFigure& figure);

// Renders `figure` and writes it to `path` atomically (WriteFileAtomically). The error names
// the path.
[[nodiscard]] Status WriteSvg(const PlotFigure& figure, const std::string& path);

// `text` with &, <, >, " and ' replaced by XML entities.
std::string XmlEscape(const std::string& text);

// Tick positions covering [lo, hi] with a step of 1, 2 or 5 times a power of ten, about
// `target_count` ticks. The first tick is <= lo and the last >= hi. lo < hi, both finite.
std::vector<double> NiceTicks(double lo, double hi, int target_count);

}  // namespace rigcal::plot
