// SPDX-License-Identifier: Apache-2.0
#pragma once
// The figures of the report, built from its data (report_data.h).

#include <string>
#include <utility>
#include <vector>

#include "rigcal/report/report_data.h"

namespace rigcal::report::internal {

// One figure of the page: its SVG, or why there is none.
struct ReportFigure {
  std::string name;     // data-plot attribute, unique in the page
  std::string title;    // caption
  std::string note;     // a sentence under the title (what is shown, what is left out)
  std::string svg;      // the bare <svg> element; empty when missing
  std::string missing;  // why there is no plot (when svg is empty)
  // data-<name>="value" attributes of the <figure>: the plotted numbers for a reader.
  std::vector<std::pair<std::string, std::string>> attributes = {};
};

// Per slave: every parameter over time with ±σ bands and the truth.
std::vector<ReportFigure> HistoryFigures(const ReportData& data);
// Per slave: measured scales with the rejection threshold (fig. 5.12), and the constraint
// residua over time (fig. 5.11).
std::vector<ReportFigure> MotionFigures(const ReportData& data);
// Per slave: histograms of the per-motion rotation and position residua with their σ
// (residual_histograms.cc).
ReportFigure HistogramFigure(const std::string& slave, const SlaveMotions& motions,
                             const std::string& distance_unit);
// The cameras' VO health over time: fps, drops, VO state, pose age.
ReportFigure HealthFigure(const ReportData& data);
// The rig from the top and from the side with camera frusta.
ReportFigure RigViewFigure(const ReportData& data);

}  // namespace rigcal::report::internal
