// SPDX-License-Identifier: Apache-2.0
// Output of the thesis experiments: CSV, SVG figures, the text summary and writing them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "rigcal/base/format.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/research/experiments.h"

namespace rigcal::research {
namespace {

std::string CsvNumber(double v) { return std::isfinite(v) ? SignificantText(v, 6) : ""; }

// Fixed-width cell; "-" for unavailable values.
std::string Cell(double v, int width = 8, int decimals = 3) {
  char buf[64];
  if (!std::isfinite(v)) {
    std::snprintf(buf, sizeof(buf), "%*s", width, "-");
  } else {
    std::snprintf(buf, sizeof(buf), "%*.*f", width, decimals, v);
  }
  return buf;
}

std::string Text(const std::string& s, int width) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), "%*s", width, s.c_str());
  return buf;
}

bool SweepsPoses(const ExperimentResult& r) { return r.kind == ExperimentKind::kPoses; }

// x of a row in the figures of stability / poses.
double StabilityX(const ExperimentResult& r, const ExperimentRow& row) {
  return SweepsPoses(r) ? row.num_poses : row.eps_deg;
}

std::vector<const ExperimentRow*> RowsOf(const ExperimentResult& r, const std::string& series) {
  std::vector<const ExperimentRow*> rows;
  for (const ExperimentRow& row : r.rows) {
    if (row.series == series) rows.push_back(&row);
  }
  return rows;
}

int SampleCount(const ExperimentResult& r) {
  return r.rows.empty() ? 0 : r.rows.front().errors.usable + r.rows.front().errors.failed;
}

plot::PlotFigure StabilityFigure(const ExperimentResult& r, const std::string& series,
                           const std::string& title) {
  struct Measure {
    const char* title;
    const char* unit;
    double ErrorStats::*mean;
    double ErrorStats::*rms;
    double ErrorStats::*median;
    double BoundStats::*bound;
  };
  const Measure measures[] = {
      {"(a) rotation orientation error", "deg", &ErrorStats::rot_mean_deg, &ErrorStats::rot_rms_deg,
       &ErrorStats::rot_median_deg, &BoundStats::rot_deg},
      {"(b) position orientation error", "deg", &ErrorStats::dir_mean_deg, &ErrorStats::dir_rms_deg,
       &ErrorStats::dir_median_deg, &BoundStats::dir_deg},
      {"(c) distance error", "%", &ErrorStats::dist_mean_pct, &ErrorStats::dist_rms_pct,
       &ErrorStats::dist_median_pct, &BoundStats::dist_pct},
      {"(d) scale error", "%", &ErrorStats::scale_mean_pct, &ErrorStats::scale_rms_pct,
       &ErrorStats::scale_median_pct, &BoundStats::scale_pct},
  };
  const auto rows = RowsOf(r, series);
  plot::PlotFigure figure;
  figure.title = title;
  figure.columns = 2;
  for (const Measure& m : measures) {
    plot::PlotPanel panel;
    panel.title = m.title;
    panel.x_label = SweepsPoses(r) ? "number of poses K" : "orientation error level eps [deg]";
    panel.y_label = std::string("error [") + m.unit + "]";
    // Errors grow with eps and fall with K: keep the legend where the curves are low.
    panel.legend = SweepsPoses(r) ? plot::LegendPosition::kTopRight : plot::LegendPosition::kTopLeft;
    plot::PlotSeries mean{"mean", {}, {}, "#0072B2", false, true};
    plot::PlotSeries rms{"RMS", {}, {}, "#D55E00", false, false};
    plot::PlotSeries median{"median", {}, {}, "#009E73", false, false};
    plot::PlotSeries bound{"Cramer-Rao bound (RMS)", {}, {}, "#000000", true, false};
    for (const ExperimentRow* row : rows) {
      const double x = StabilityX(r, *row);
      mean.x.push_back(x);
      mean.y.push_back(row->errors.*m.mean);
      rms.x.push_back(x);
      rms.y.push_back(row->errors.*m.rms);
      median.x.push_back(x);
      median.y.push_back(row->errors.*m.median);
      bound.x.push_back(x);
      bound.y.push_back(row->crb.*m.bound);
    }
    panel.series = {mean, median, rms};
    bool has_bound = false;
    for (double y : bound.y) has_bound = has_bound || std::isfinite(y);
    if (has_bound) panel.series.push_back(bound);
    figure.panels.push_back(panel);
  }
  return figure;
}

// Errors of both models per eps (solid: alternative, dashed: simple) and the boundary.
plot::PlotFigure ComparisonFigure(const ExperimentResult& r, const std::string& title) {
  const bool motion = r.kind == ExperimentKind::kMotionModel;
  const std::string simple = motion ? "translational" : "fixed";
  const std::string alternative = motion ? "general" : "time-dependent";
  auto swept = [motion](const ExperimentRow& row) {
    return motion ? row.alpha_max_deg : row.max_scale_error_pct;
  };
  auto metric = [motion](const ExperimentRow& row) {
    return motion ? row.errors.rot_mean_deg : row.errors.dir_mean_deg;
  };
  const char* palette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9"};

  plot::PlotPanel errors;
  errors.title = motion ? "rotation orientation error" : "position orientation error";
  errors.x_label = motion ? "maximal rig rotation alpha_max [deg]" : "maximal scale error [%]";
  errors.y_label = "mean error [deg]";
  errors.legend = plot::LegendPosition::kOutsideRight;
  std::map<double, size_t> color_of_eps;
  double simple_max = 0.0;
  for (const std::string& series : {alternative, simple}) {
    std::map<double, plot::PlotSeries> by_eps;
    for (const ExperimentRow* row : RowsOf(r, series)) {
      plot::PlotSeries& s = by_eps[row->eps_deg];
      s.x.push_back(swept(*row));
      s.y.push_back(metric(*row));
      if (series == simple && std::isfinite(metric(*row))) {
        simple_max = std::max(simple_max, metric(*row));
      }
    }
    for (auto& [eps, s] : by_eps) {
      if (!color_of_eps.count(eps)) color_of_eps[eps] = color_of_eps.size();
      char label[96];
      std::snprintf(label, sizeof(label), "%s, eps = %g deg", series.c_str(), eps);
      s.label = label;
      s.color = palette[color_of_eps[eps] % 6];
      s.dashed = series == simple;
      s.markers = !s.dashed;
      errors.series.push_back(s);
    }
  }
  // The general model's error explodes at small rotations; keep the interesting range visible.
  if (motion && simple_max > 0.0) {
    for (plot::PlotSeries& s : errors.series) {
      for (double& y : s.y) {
        if (y > 3.0 * simple_max) y = std::nan("");
      }
    }
    errors.title += " (values above 3x the translational maximum not drawn)";
  }

  plot::PlotPanel boundary;
  boundary.title = "equal-error boundary (" + alternative + " better above)";
  boundary.x_label = "orientation error level eps [deg]";
  boundary.y_label = motion ? "alpha_max [deg]" : "maximal scale error [%]";
  plot::PlotSeries line{"boundary", {}, {}, "#000000", false, true};
  for (const EqualErrorBoundary& b : r.boundary) {
    line.x.push_back(b.eps_deg);
    line.y.push_back(b.value);
  }
  boundary.series.push_back(line);

  plot::PlotFigure figure;
  figure.title = title;
  figure.panels = {errors, boundary};
  figure.columns = 1;
  figure.panel_width = 820;
  figure.panel_height = 400;
  return figure;
}

std::string StabilitySummary(const ExperimentResult& r) {
  std::ostringstream out;
  const auto lls = RowsOf(r, "lls");
  const auto nl = RowsOf(r, "nl");
  out << "               -------- LLS mean ---------   --------- NL mean ---------   "
         "---------- NL RMS ---------   -------- CRB (RMS) --------\n";
  out << (SweepsPoses(r) ? "     K" : "   eps");
  for (int block = 0; block < 4; ++block) out << "     rot    dir   dist  scale";
  out << "  failed\n";
  out << (SweepsPoses(r) ? "      " : " [deg]");
  for (int block = 0; block < 4; ++block) out << "   [deg]  [deg]    [%]    [%]";
  out << "\n";
  for (size_t i = 0; i < lls.size() && i < nl.size(); ++i) {
    const ErrorStats& a = lls[i]->errors;
    const ErrorStats& b = nl[i]->errors;
    const BoundStats& c = nl[i]->crb;
    if (SweepsPoses(r)) {
      out << Text(std::to_string(lls[i]->num_poses), 6);
    } else {
      out << Cell(lls[i]->eps_deg, 6, 1);
    }
    out << "  " << Cell(a.rot_mean_deg, 6) << Cell(a.dir_mean_deg, 7) << Cell(a.dist_mean_pct, 7)
        << Cell(a.scale_mean_pct, 7);
    out << "  " << Cell(b.rot_mean_deg, 6) << Cell(b.dir_mean_deg, 7) << Cell(b.dist_mean_pct, 7)
        << Cell(b.scale_mean_pct, 7);
    out << "  " << Cell(b.rot_rms_deg, 6) << Cell(b.dir_rms_deg, 7) << Cell(b.dist_rms_pct, 7)
        << Cell(b.scale_rms_pct, 7);
    out << "  " << Cell(c.rot_deg, 6) << Cell(c.dir_deg, 7) << Cell(c.dist_pct, 7)
        << Cell(c.scale_pct, 7);
    out << Text(std::to_string(a.failed) + "/" + std::to_string(b.failed), 8) << "\n";
  }
  return out.str();
}

std::string ComparisonSummary(const ExperimentResult& r) {
  const bool motion = r.kind == ExperimentKind::kMotionModel;
  const std::string simple = motion ? "translational" : "fixed";
  const std::string alternative = motion ? "general" : "time-dependent";
  // table[swept][eps] = (simple, alternative) mean error
  std::map<double, std::map<double, std::pair<double, double>>> table;
  std::map<double, std::pair<int, int>> failures;  // per eps
  std::vector<double> eps_levels;
  for (const ExperimentRow& row : r.rows) {
    const double x = motion ? row.alpha_max_deg : row.max_scale_error_pct;
    const double v = motion ? row.errors.rot_mean_deg : row.errors.dir_mean_deg;
    auto& cell = table[x][row.eps_deg];
    if (row.series == simple) {
      cell.first = v;
      failures[row.eps_deg].first += row.errors.failed;
    } else {
      cell.second = v;
      failures[row.eps_deg].second += row.errors.failed;
    }
  }
  for (const auto& [eps, f] : failures) eps_levels.push_back(eps);

  std::ostringstream out;
  out << (motion ? "mean rotation orientation error [deg]: "
                 : "mean position orientation error [deg]: ")
      << "G = " << alternative << ", S = " << simple << "\n";
  out << (motion ? "alpha_max" : "scale err");
  for (double eps : eps_levels) {
    char head[64];
    std::snprintf(head, sizeof(head), "   G(eps=%g)  S(eps=%g)", eps, eps);
    out << head;
  }
  out << "\n";
  for (const auto& [x, by_eps] : table) {
    out << Cell(x, 9, motion ? 0 : 0);
    for (double eps : eps_levels) {
      auto it = by_eps.find(eps);
      const double g = it == by_eps.end() ? kNotAvailable : it->second.second;
      const double s = it == by_eps.end() ? kNotAvailable : it->second.first;
      char head[64];
      std::snprintf(head, sizeof(head), "   G(eps=%g)  S(eps=%g)", eps, eps);
      const int w = static_cast<int>(std::string(head).size());
      const int half = w / 2;
      out << Cell(g, half, 3) << Cell(s, w - half, 3);
    }
    out << "\n";
  }
  out << "failures (S/G, all points of one eps):";
  for (const auto& [eps, f] : failures) {
    out << " eps=" << eps << ": " << f.first << "/" << f.second;
  }
  out << "\nequal-error boundary (" << alternative << " more accurate from):\n";
  for (const EqualErrorBoundary& b : r.boundary) {
    char line[128];
    if (std::isfinite(b.value)) {
      std::snprintf(line, sizeof(line), "  eps = %g deg: %s >= %g %s\n", b.eps_deg,
                    motion ? "alpha_max" : "max scale error", b.value, motion ? "deg" : "%");
    } else {
      std::snprintf(line, sizeof(line), "  eps = %g deg: not within the grid\n", b.eps_deg);
    }
    out << line;
  }
  return out.str();
}

}  // namespace

std::string ExperimentCsv(const ExperimentResult& result) {
  std::ostringstream out;
  out << "experiment,series,eps_deg,num_poses,alpha_max_deg,max_scale_error_pct,usable,failed,"
         "rot_mean_deg,rot_rms_deg,rot_median_deg,dir_mean_deg,dir_rms_deg,dir_median_deg,"
         "dist_mean_pct,dist_rms_pct,dist_median_pct,scale_mean_pct,scale_rms_pct,"
         "scale_median_pct,crb_rot_deg,crb_dir_deg,crb_dist_pct,crb_scale_pct\n";
  const std::string name = ToString(result.kind);
  for (const ExperimentRow& row : result.rows) {
    const ErrorStats& e = row.errors;
    out << name << ',' << row.series << ',' << CsvNumber(row.eps_deg) << ',' << row.num_poses << ','
        << CsvNumber(row.alpha_max_deg) << ',' << CsvNumber(row.max_scale_error_pct) << ','
        << e.usable << ',' << e.failed;
    for (double v : {e.rot_mean_deg, e.rot_rms_deg, e.rot_median_deg, e.dir_mean_deg, e.dir_rms_deg,
                     e.dir_median_deg, e.dist_mean_pct, e.dist_rms_pct, e.dist_median_pct,
                     e.scale_mean_pct, e.scale_rms_pct, e.scale_median_pct, row.crb.rot_deg,
                     row.crb.dir_deg, row.crb.dist_pct, row.crb.scale_pct}) {
      out << ',' << CsvNumber(v);
    }
    out << '\n';
  }
  const bool motion = result.kind == ExperimentKind::kMotionModel;
  for (const EqualErrorBoundary& b : result.boundary) {
    out << name << ",equal_error_boundary," << CsvNumber(b.eps_deg) << ",";
    out << (result.rows.empty() ? 0 : result.rows.front().num_poses) << ',';
    out << (motion ? CsvNumber(b.value) : "") << ',' << (motion ? "" : CsvNumber(b.value));
    out << std::string(18, ',') << '\n';  // usable .. crb_scale_pct empty
  }
  return out.str();
}

std::vector<NamedFigure> ExperimentFigures(const ExperimentResult& result) {
  const std::string n = std::to_string(SampleCount(result));
  const std::string k = result.rows.empty() ? "?" : std::to_string(result.rows.front().num_poses);
  std::vector<NamedFigure> figures;
  switch (result.kind) {
    case ExperimentKind::kStability:
      figures.push_back(
          {"fig5_1_lls.svg", StabilityFigure(result, "lls",
                                             "Fig. 5.1: linear least squares, K = " + k + ", " + n +
                                                 " samples per point")});
      figures.push_back(
          {"fig5_2_nl.svg", StabilityFigure(result, "nl",
                                            "Fig. 5.2: non-linear refinement, K = " + k + ", " + n +
                                                " samples per point")});
      break;
    case ExperimentKind::kPoses:
      figures.push_back(
          {"fig5_3_lls.svg", StabilityFigure(result, "lls",
                                             "Fig. 5.3: linear least squares, eps = 1 deg, " + n +
                                                 " samples per point")});
      figures.push_back(
          {"fig5_4_nl.svg", StabilityFigure(result, "nl",
                                            "Fig. 5.4: non-linear refinement, eps = 1 deg, " + n +
                                                " samples per point")});
      break;
    case ExperimentKind::kMotionModel:
      figures.push_back(
          {"fig5_5.svg", ComparisonFigure(result,
                                          "Fig. 5.5: general vs purely translational motion model "
                                          "(LLS), " +
                                              n + " samples per point")});
      break;
    case ExperimentKind::kScaleModel:
      figures.push_back(
          {"fig5_6.svg",
           ComparisonFigure(result, "Fig. 5.6: time-fixed vs time-dependent scale model (LLS), " +
                                        n + " samples per point")});
      break;
  }
  return figures;
}

std::string FormatSummary(const ExperimentResult& result) {
  std::ostringstream out;
  out << "experiment " << ToString(result.kind) << "\n";
  if (!result.error.empty()) {
    out << "error: " << result.error << "\n";
    return out.str();
  }
  if (result.kind == ExperimentKind::kStability || result.kind == ExperimentKind::kPoses) {
    out << StabilitySummary(result);
  } else {
    out << ComparisonSummary(result);
  }
  out << "notes:\n";
  for (const std::string& note : result.notes) out << "  - " << note << "\n";
  return out.str();
}

Expected<std::vector<std::string>> WriteExperimentOutputs(const ExperimentResult& result,
                                                          const std::string& out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return Error{"cannot create directory '" + out_dir + "': " + ec.message()};
  const std::filesystem::path dir(out_dir);
  const std::string name = ToString(result.kind);
  std::vector<std::string> written;
  const std::pair<std::string, std::string> texts[] = {
      {name + ".csv", ExperimentCsv(result)}, {name + "_summary.txt", FormatSummary(result)}};
  for (const auto& [file, content] : texts) {
    const std::string path = (dir / file).string();
    if (Status status = io::WriteFileAtomically(path, content); !status.ok()) return status;
    written.push_back(path);
  }
  for (const NamedFigure& figure : ExperimentFigures(result)) {
    const std::string path = (dir / figure.file_name).string();
    if (Status status = plot::WriteSvg(figure.figure, path); !status.ok()) return status;
    written.push_back(path);
  }
  return written;
}

ExperimentResult NewExperimentResult(ExperimentKind kind, const ExperimentOptions& options) {
  ExperimentResult result;
  result.kind = kind;
  result.error = options.Check().message();
  return result;
}

}  // namespace rigcal::research
