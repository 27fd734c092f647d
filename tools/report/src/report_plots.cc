// SPDX-License-Identifier: Apache-2.0
#include "report_plots.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "rigcal/base/format.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/plot/svg_plot.h"

namespace rigcal::report::internal {
namespace {

constexpr const char* kAxisColors[] = {"#D55E00", "#009E73", "#0072B2"};  // x, y, z
constexpr const char* kAxisNames[] = {"x", "y", "z"};
// Besides its colour every line of a camera or an axis has its own dash pattern and marker, so
// the lines stay apart in grey print and for colour-blind readers.
constexpr const char* kDashes[] = {"", "7 3", "2 2", "7 2 2 2", "12 3", "4 4"};
constexpr plot::Marker kMarkers[] = {plot::Marker::kCircle, plot::Marker::kSquare,
                                     plot::Marker::kTriangle, plot::Marker::kDiamond,
                                     plot::Marker::kCross};
constexpr const char* kCameraColors[] = {"#000000", "#0072B2", "#D55E00", "#009E73",
                                         "#CC79A7", "#E69F00", "#56B4E9"};

// The style of line `index` of a plot whose lines are cameras or axes.
void StyleLine(size_t index, plot::PlotSeries* s, bool colour = true) {
  if (colour) s->color = kCameraColors[index % std::size(kCameraColors)];
  s->dash_array = kDashes[index % std::size(kDashes)];
  s->marker = kMarkers[index % std::size(kMarkers)];
}

// The rotation from `reference` to `q` as a rotation vector θ·axis in degrees, expressed in the
// master frame: small and continuous near the reference, where the components of q's own
// rotation vector or its roll/pitch/yaw may jump (at 180° or at pitch ±90°).
Eigen::Vector3d RotationFromDeg(const Eigen::Quaterniond& reference, const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(Canonical(q * reference.conjugate()));
  return aa.axis() * aa.angle() * kDegPerRad;
}

std::string Slug(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
  return out;
}

ReportFigure Missing(const std::string& name, const std::string& title, const std::string& why) {
  ReportFigure f;
  f.name = name;
  f.title = title;
  f.missing = why;
  return f;
}

// Points of a line series are marked when there are few of them (a single point has no line).
constexpr size_t kMarkBelowPoints = 30;

ReportFigure Drawn(const std::string& name, const std::string& title, plot::PlotFigure figure,
                   const std::string& note = "") {
  figure.id_prefix = Slug(name) + "-";
  for (plot::PlotPanel& panel : figure.panels) {
    for (plot::PlotSeries& series : panel.series) {
      if (series.x.size() < kMarkBelowPoints) series.markers = true;
    }
  }
  ReportFigure f;
  f.name = name;
  f.title = title;
  f.note = note;
  f.svg = plot::RenderSvgElement(figure);
  return f;
}

// A line (markers only when few points, see Drawn) or, with `scatter`, markers only.
plot::PlotSeries Series(const std::string& label, const std::string& color, bool scatter = false) {
  plot::PlotSeries s;
  s.label = label;
  s.color = color;
  s.lines = !scatter;
  s.markers = scatter;
  return s;
}

plot::PlotSeries Scatter(const std::string& label, const std::string& color) {
  return Series(label, color, true);
}

// Three components over time with ±σ bands and the truth as dashed lines in their colours.
// values[k] and sigmas[k] belong to samples[k].
plot::PlotPanel VectorPanel(const std::string& title, const std::string& y_label,
                            const std::vector<EstimateSample>& samples,
                            const std::vector<Eigen::Vector3d>& values,
                            const std::vector<Eigen::Vector3d>& sigmas,
                            const std::optional<Eigen::Vector3d>& truth) {
  plot::PlotPanel panel;
  panel.title = title;
  panel.x_label = "time [s]";
  panel.y_label = y_label;
  panel.y_from_zero = false;
  panel.legend = plot::LegendPosition::kOutsideRight;
  for (int i = 0; i < 3; ++i) {
    plot::PlotSeries s = Series(kAxisNames[i], kAxisColors[i]);
    StyleLine(i, &s, false);
    for (size_t k = 0; k < samples.size(); ++k) {
      const double v = values[k][i];
      const double sd = sigmas[k][i];
      s.x.push_back(samples[k].t_s);
      s.y.push_back(v);
      s.band_lo.push_back(v - sd);  // NaN σ (unknown): no band there
      s.band_hi.push_back(v + sd);
    }
    panel.series.push_back(std::move(s));
    if (truth) {
      panel.reference_lines.push_back(
          {(*truth)[i], std::string("true ") + kAxisNames[i], kAxisColors[i], true});
    }
  }
  return panel;
}

// Usable estimates only: an initialising slave's values are placeholders.
std::vector<EstimateSample> UsableSamples(const std::vector<EstimateSample>& samples) {
  std::vector<EstimateSample> out;
  for (const EstimateSample& e : samples) {
    if (IsUsable(e.state) || e.state == SlaveState::kDecalibrated) out.push_back(e);
  }
  return out;
}

const Similarity* TruthOf(const ReportData& data, const std::string& slave) {
  const auto it = data.truth.find(slave);
  return it == data.truth.end() ? nullptr : &it->second;
}

// A y range that shows the bulk of `values` around `centre` (robust: median ± 8 MAD σ, at least
// ±20 % of the centre), so a few degenerate measured scales do not flatten the plot.
std::pair<double, double> RobustRange(std::vector<double> values, double centre) {
  if (values.empty()) return {centre * 0.8, centre * 1.2};
  const double median = UpperMedian(values);
  for (double& v : values) v = std::abs(v - median);
  const double spread = 1.4826 * UpperMedian(values);
  const double half = std::max({8.0 * spread, 0.2 * std::abs(centre), 1e-9});
  const double lo = std::min(median, centre) - half;
  const double hi = std::max(median, centre) + half;
  return {lo, hi};
}

ReportFigure ScaleFigure(const ReportData& data, const std::string& slave,
                         const SlaveMotions& motions) {
  plot::PlotPanel scales;
  scales.title = "measured scales λ^k (4.18) per motion";
  scales.x_label = "time [s]";
  scales.y_label = "scale";
  scales.y_from_zero = false;
  scales.legend = plot::LegendPosition::kOutsideRight;
  plot::PlotSeries used = Scatter("used", "#0072B2");
  plot::PlotSeries rejected = Scatter("rejected", "#D55E00");
  rejected.marker = plot::Marker::kCross;
  std::vector<double> used_values;
  int outside = 0;
  for (const MotionSample& m : motions.samples) {
    if (!std::isfinite(m.measured_scale)) continue;
    plot::PlotSeries& s = m.scale_used ? used : rejected;
    s.x.push_back(m.t_s);
    s.y.push_back(m.measured_scale);
    if (m.scale_used) used_values.push_back(m.measured_scale);
  }
  const auto [lo, hi] = RobustRange(used_values, motions.reference_scale);
  for (const plot::PlotSeries* s : {&used, &rejected}) {
    for (double v : s->y) outside += v < lo || v > hi;
  }
  scales.y_min = lo;
  scales.y_max = hi;
  scales.series = {used, rejected};
  scales.reference_lines.push_back({motions.reference_scale, "final estimate", "#000000", false});
  if (!used_values.empty()) {
    double mean = 0.0;
    for (double v : used_values) mean += v;
    mean /= static_cast<double>(used_values.size());
    scales.reference_lines.push_back({mean, "mean of used", "#0072B2", true});
  }
  if (const Similarity* truth = TruthOf(data, slave); truth && std::isfinite(truth->scale)) {
    scales.reference_lines.push_back({truth->scale, "truth", "#009E73", true});
  }

  // C₀ᵀr₀ is in the master's unit, Cᵢᵀrᵢ in the slave odometry's own: the legend says which.
  plot::PlotPanel dots;
  dots.title = "C₀ᵀr₀ and Cᵢᵀrᵢ per motion (4.18)";
  dots.x_label = "time [s]";
  dots.y_label = "Cᵀr [odometry unit of each camera]";
  dots.y_from_zero = true;
  dots.legend = plot::LegendPosition::kOutsideRight;
  const std::string master_unit = data.distance_unit == "m" ? "m" : "master unit";
  plot::PlotSeries master = Scatter(data.master + ": C₀ᵀr₀ [" + master_unit + "]", "");
  plot::PlotSeries slave_dot = Scatter(slave + ": Cᵢᵀrᵢ [" + slave + " unit]", "");
  StyleLine(0, &master);
  StyleLine(1, &slave_dot);
  for (const MotionSample& m : motions.samples) {
    master.x.push_back(m.t_s);
    master.y.push_back(m.master_axis_dot);
    slave_dot.x.push_back(m.t_s);
    slave_dot.y.push_back(m.slave_axis_dot);
  }
  dots.series = {master, slave_dot};
  dots.reference_lines.push_back({motions.scale_threshold, "±δ (4.23)", "#D55E00", true});
  dots.reference_lines.push_back({-motions.scale_threshold, "", "#D55E00", true});

  plot::PlotFigure figure;
  figure.panels = {scales, dots};
  figure.columns = 2;
  figure.panel_width = 560;
  figure.panel_height = 300;
  const std::string note =
      std::to_string(used.y.size()) + " scales used, " + std::to_string(rejected.y.size()) +
      " rejected (δ = " + SignificantText(motions.scale_threshold, 3) + ")" +
      (outside > 0 ? "; " + std::to_string(outside) + " beyond the plotted range not shown" : "");
  return Drawn("scales-" + slave, slave + ": measured scales (thesis fig. 5.12)", figure, note);
}

ReportFigure ResidualFigure(const std::string& slave, const SlaveMotions& motions,
                            const std::string& distance_unit) {
  auto panel = [&](const std::string& title, const std::string& y_label,
                   double MotionSample::*field) {
    plot::PlotPanel p;
    p.title = title;
    p.x_label = "time [s]";
    p.y_label = y_label;
    plot::PlotSeries s = Scatter("", "#0072B2");
    for (const MotionSample& m : motions.samples) {
      s.x.push_back(m.t_s);
      s.y.push_back(m.*field);
    }
    p.series = {s};
    return p;
  };
  plot::PlotFigure figure;
  figure.panels = {
      panel("rotation constraint residuum", "angle [deg]", &MotionSample::rotation_deg),
      panel("position constraint residuum (direction)", "angle [deg]",
            &MotionSample::position_dir_deg),
      panel("position constraint residuum", "|residual| [" + distance_unit + "]",
            &MotionSample::position_abs)};
  figure.columns = 3;
  figure.panel_width = 380;
  figure.panel_height = 280;
  return Drawn("residua-" + slave, slave + ": constraint residua (thesis fig. 5.11)", figure,
               std::to_string(motions.samples.size()) + " motions, against the final estimate");
}

}  // namespace

std::vector<ReportFigure> HistoryFigures(const ReportData& data) {
  std::vector<ReportFigure> out;
  for (const std::string& slave : data.slaves) {
    const std::string name = "history-" + slave;
    const std::string title = slave + ": parameters over time (±1σ bands)";
    if (!data.from_log) {
      out.push_back(Missing(name, title, "no history in a result file"));
      continue;
    }
    const auto it = data.estimates.find(slave);
    const std::vector<EstimateSample> samples =
        it == data.estimates.end() ? std::vector<EstimateSample>() : UsableSamples(it->second);
    if (samples.empty()) {
      out.push_back(Missing(name, title, "no usable estimate in the log's RIGCAL_EXTRINSICS"));
      continue;
    }
    const Similarity* truth = TruthOf(data, slave);
    const Eigen::Quaterniond final_q = samples.back().estimate.q;
    plot::PlotFigure figure;
    figure.columns = 2;
    figure.panel_width = 560;
    figure.panel_height = 280;
    std::vector<Eigen::Vector3d> rotation, rotation_sigma, position, position_sigma;
    for (const EstimateSample& e : samples) {
      rotation.push_back(RotationFromDeg(final_q, e.estimate.q));
      rotation_sigma.push_back(Eigen::Vector3d::Constant(e.rot_std_deg));
      position.push_back(e.estimate.C);
      position_sigma.push_back(e.pos_std);
    }
    figure.panels.push_back(VectorPanel(
        "rotation relative to the final estimate", "rotation vector [deg]", samples, rotation,
        rotation_sigma,
        truth ? std::optional<Eigen::Vector3d>(RotationFromDeg(final_q, truth->q)) : std::nullopt));
    figure.panels.push_back(
        VectorPanel("position C", "[" + data.distance_unit + "]", samples, position, position_sigma,
                    truth ? std::optional<Eigen::Vector3d>(truth->C) : std::nullopt));
    auto time_panel = [](const std::string& t, const std::string& y_label, bool from_zero) {
      plot::PlotPanel p;
      p.title = t;
      p.x_label = "time [s]";
      p.y_label = y_label;
      p.y_from_zero = from_zero;
      p.legend = plot::LegendPosition::kOutsideRight;
      return p;
    };
    plot::PlotPanel scale = time_panel("scale (current segment)", "slave → master units", false);
    plot::PlotPanel used = time_panel("motions used", "motions", true);
    plot::PlotPanel rot_sigma = time_panel("σ rotation", "[deg]", true);
    plot::PlotPanel pos_sigma = time_panel("σ C", "[" + data.distance_unit + "]", true);
    plot::PlotSeries s = Series("scale", "#0072B2");
    plot::PlotSeries n = Series("used", "#0072B2");
    plot::PlotSeries r = Series("σ rot", "#0072B2");
    std::vector<plot::PlotSeries> c;
    for (int i = 0; i < 3; ++i)
      c.push_back(Series(std::string("σ ") + kAxisNames[i], kAxisColors[i]));
    for (const EstimateSample& e : samples) {
      s.x.push_back(e.t_s);
      s.y.push_back(e.estimate.scale);
      s.band_lo.push_back(e.estimate.scale - e.scale_std);
      s.band_hi.push_back(e.estimate.scale + e.scale_std);
      n.x.push_back(e.t_s);
      n.y.push_back(e.motions_used);
      r.x.push_back(e.t_s);
      r.y.push_back(e.rot_std_deg);
      for (int i = 0; i < 3; ++i) {
        c[i].x.push_back(e.t_s);
        c[i].y.push_back(e.pos_std[i]);
      }
    }
    scale.series = {s};
    if (truth && std::isfinite(truth->scale))
      scale.reference_lines.push_back({truth->scale, "truth", "#009E73", true});
    used.series = {n};
    rot_sigma.series = {r};
    pos_sigma.series = c;
    figure.panels.insert(figure.panels.end(), {scale, used, rot_sigma, pos_sigma});
    out.push_back(Drawn(name, title, figure,
                        std::to_string(samples.size()) + " usable estimates of " +
                            std::to_string(it->second.size()) + " messages" +
                            (truth ? "; dashed: the truth" : "")));
  }
  return out;
}

std::vector<ReportFigure> MotionFigures(const ReportData& data) {
  std::vector<ReportFigure> out;
  for (const std::string& slave : data.slaves) {
    const std::string why =
        "no poses: give the pose log (--poses LOG, or RIGCAL_POSE_<camera> events in the log)";
    const SlaveMotions* motions = nullptr;
    if (data.motions) {
      const auto it = data.motions->slaves.find(slave);
      if (it != data.motions->slaves.end() && !it->second.samples.empty()) motions = &it->second;
    }
    if (motions == nullptr) {
      const std::string reason = data.motions ? "no motions of this slave in the poses" : why;
      out.push_back(
          Missing("scales-" + slave, slave + ": measured scales (thesis fig. 5.12)", reason));
      out.push_back(
          Missing("residua-" + slave, slave + ": constraint residua (thesis fig. 5.11)", reason));
      out.push_back(
          Missing("histograms-" + slave, slave + ": residua per motion (histograms)", reason));
      continue;
    }
    out.push_back(ScaleFigure(data, slave, *motions));
    out.push_back(ResidualFigure(slave, *motions, data.distance_unit));
    out.push_back(HistogramFigure(slave, *motions, data.distance_unit));
  }
  return out;
}

ReportFigure HealthFigure(const ReportData& data) {
  const std::string name = "camera-health";
  const std::string title = "camera VO health (RIGCAL_STATUS)";
  if (!data.from_log) return Missing(name, title, "no history in a result file");
  if (data.health.empty()) return Missing(name, title, "no RIGCAL_STATUS message in the log");
  // The cameras whose clock runs free (an offset in some message).
  std::vector<std::string> free_running;
  for (const std::string& camera : data.cameras) {
    const std::vector<CameraHealthSample>& samples = data.health.at(camera);
    if (std::any_of(samples.begin(), samples.end(),
                    [](const CameraHealthSample& h) { return std::isfinite(h.time_offset_ms); })) {
      free_running.push_back(camera);
    }
  }
  auto panel = [&](const std::string& t, const std::string& y_label,
                   double (*value)(const CameraHealthSample&), bool clocks = false) {
    plot::PlotPanel p;
    p.title = t;
    p.x_label = "time [s]";
    p.y_label = y_label;
    p.legend = plot::LegendPosition::kOutsideRight;
    for (const std::string& camera : clocks ? free_running : data.cameras) {
      plot::PlotSeries s;
      s.label = camera;
      s.markers = true;
      const auto index = std::find(data.cameras.begin(), data.cameras.end(), camera);
      StyleLine(static_cast<size_t>(index - data.cameras.begin()), &s);
      for (const CameraHealthSample& h : data.health.at(camera)) {
        s.x.push_back(h.t_s);
        s.y.push_back(value(h));
      }
      p.series.push_back(std::move(s));
    }
    return p;
  };
  plot::PlotPanel vo_state =
      panel("VO state", "0 init · 1 tracking · 2 lost · 3 dead",
            [](const CameraHealthSample& h) { return static_cast<double>(h.vo_state); });
  vo_state.y_min = 0.0;
  vo_state.y_max = 3.0;
  vo_state.y_tick_count = 4;
  plot::PlotFigure figure;
  figure.columns = 2;
  figure.panel_width = 560;
  figure.panel_height = 280;
  figure.panels = {
      panel("frame rate", "fps", [](const CameraHealthSample& h) { return h.fps; }),
      panel("dropped (all causes, cumulative)", "poses",
            [](const CameraHealthSample& h) { return static_cast<double>(h.dropped); }),
      vo_state,
      panel("age of the newest pose", "ms",
            [](const CameraHealthSample& h) {
              return h.last_pose_age_ms >= 0 ? static_cast<double>(h.last_pose_age_ms) : kUnknown;
            }),
      panel("relocalisations (cumulative; tracking regained, same segment)", "relocalisations",
            [](const CameraHealthSample& h) { return static_cast<double>(h.relocalisations); })};
  if (data.free_running && !free_running.empty()) {
    // Cameras that run free: each slave's clock offset (gaps while it is being estimated) and
    // the restarts of its clock.
    figure.panels.push_back(panel(
        "clock offset to the master", "ms",
        [](const CameraHealthSample& h) { return h.time_offset_ms; }, true));
    figure.panels.push_back(panel(
        "clock jumps (cumulative)", "jumps",
        [](const CameraHealthSample& h) { return static_cast<double>(h.clock_jumps); }, true));
  }
  return Drawn(name, title, figure,
               std::to_string(data.status_messages) +
                   " RIGCAL_STATUS messages; time since the "
                   "first one");
}

}  // namespace rigcal::report::internal
