// SPDX-License-Identifier: Apache-2.0
#pragma once
// `rigcal report`'s HTML page: one self-contained file (inline SVG and CSS, one small inline
// script, nothing fetched) that shows a calibration:
//   - notes: what is missing and why, the inputs' problems, how the truth was aligned;
//   - the final table in the thesis's error-model columns (tab. 5.1: q, C, |C|, scale, their σ,
//     and with a truth the rotation, position-direction and distance errors);
//   - the rig from the top and from the side with camera frusta (the truth dashed);
//   - per slave every parameter over time with ±σ bands and the truth (RIGCAL_EXTRINSICS);
//   - the baselines: |C| with its σ, in metres when the unit is known (metric, or fitted to a
//     truth), else the unit C is in;
//   - the cameras' intrinsics from the rig config (--config): model, fx fy cx cy, distortion,
//     resolution;
//   - per slave the measured scales per motion with the rejection threshold (fig. 5.12), the
//     rotation and position constraint residua over time (fig. 5.11) and their histograms with
//     their σ (bins and counts also as data-* attributes of the figure);
//   - per camera the VO health over time: fps, drops, VO state, pose age (RIGCAL_STATUS).
// Every plot is a <figure class="plot" data-plot="<name>">; a plot without data is a
// <figure class="plot missing"> that says why. The inline script counts the plots whose SVG
// rendered with data and writes the count into the page: <body data-plots-rendered=N
// data-plots-expected=M> and the title "... (N/M plots rendered)".

#include <string>

#include "rigcal/base/status.h"
#include "rigcal/report/report_data.h"

namespace rigcal::report {

std::string RenderReportHtml(const ReportData& data);

// Renders and writes the page atomically (WriteFileAtomically). The error names the path.
[[nodiscard]] Status WriteReportHtml(const std::string& path, const ReportData& data);

}  // namespace rigcal::report
