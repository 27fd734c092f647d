// SPDX-License-Identifier: Apache-2.0
// The published part of a slave's state (estimator_state_published.h).
#include "estimator_state_published.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <ostream>
#include <sstream>
#include <string>

namespace rigcal::io::internal {
namespace {

// A text on one line: its length, then the text with line breaks made spaces.
void WriteText(std::ostream& out, const char* label, const std::string& text) {
  std::string line = text;
  for (char& c : line) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  out << label << ' ' << line.size() << ' ' << line << '\n';
}

template <typename Derived>
void WriteNumbers(std::ostream& out, const Eigen::DenseBase<Derived>& m) {
  for (Eigen::Index i = 0; i < m.size(); ++i) out << ' ' << m.derived().data()[i];
}

void WriteObservability(std::ostream& out, const Observability& o) {
  out << "observability";
  WriteNumbers(out, o.rotation_eigenvalues);
  out << ' ' << o.rotation_weak_std_deg << ' ' << o.position_min_eigenvalue << ' '
      << o.axis_spread_deg << ' ' << o.slave_axis_spread_deg << ' ' << o.tilt_snr << ' '
      << o.axis_std_ratio << ' ' << o.max_rotation_deg << ' ' << o.rotation_noise_deg << ' '
      << o.translational_below_deg << ' ' << (o.planar ? 1 : 0);
  WriteNumbers(out, o.planar_axis);
  out << '\n';
}

void WriteCalibration(std::ostream& out, const SlaveCalibration& c) {
  out << "calibration\n";
  WriteText(out, "name", c.name);
  WriteText(out, "pairs", c.pairs);
  WriteText(out, "message", c.message);
  WriteText(out, "contradiction", c.contradiction);
  out << "kind " << static_cast<int>(c.termination) << ' ' << static_cast<int>(c.state) << ' '
      << static_cast<int>(c.motion_model) << ' ' << static_cast<int>(c.scale_model) << '\n';
  const Eigen::Quaterniond& q = c.estimate.q;
  out << "estimate " << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z();
  WriteNumbers(out, c.estimate.C);
  out << ' ' << c.estimate.scale << "\nstd " << c.rot_std_deg;
  WriteNumbers(out, c.pos_std);
  out << ' ' << c.axis_offset_std << "\nobservable " << (c.position_observable ? 1 : 0) << ' '
      << (c.unobservable_from_prior ? 1 : 0) << ' ' << c.unobservable.size();
  for (const Eigen::Vector3d& u : c.unobservable) WriteNumbers(out, u);
  out << "\nscales " << c.scales.size() << '\n';
  for (const SegmentScale& s : c.scales) {
    out << "scale " << s.segment << ' ' << s.scale << ' ' << s.std << ' ' << s.measured_mean << ' '
        << s.measured_std << ' ' << s.measured_count << '\n';
  }
  const MotionCounts& m = c.motions;
  out << "motions " << m.total << ' ' << m.used << ' ' << m.small_rotation << ' '
      << m.angle_mismatch << ' ' << m.residual_outlier << '\n';
  const GlitchCounts& g = c.glitches;
  out << "glitches " << g.position_jump << ' ' << g.rotation_jump << ' ' << g.angle_mismatch << ' '
      << g.in_master << ' ' << g.in_slave << '\n';
  WriteObservability(out, c.observability);
  out << "time_offset " << c.time_offset_s << ' ' << c.time_offset_std_s << '\n';
}

// Words of the block in order; numbers may be "nan" (strtod), never anything else.
class Tokens {
 public:
  explicit Tokens(std::string_view text) : in_(std::string(text)) {}
  bool Word(const char* expected) {
    std::string w;
    return ok_ && (in_ >> w) && w == expected ? true : Fail(expected);
  }
  double Number(const char* field) {
    std::string w;
    if (!ok_ || !(in_ >> w)) return Fail(field), 0.0;
    char* end = nullptr;
    const double v = std::strtod(w.c_str(), &end);
    if (end != w.c_str() + w.size()) return Fail(field), 0.0;
    return v;
  }
  // A finite number within ±1e100.
  double Finite(const char* field) {
    const double v = Number(field);
    return std::isfinite(v) && std::abs(v) <= 1e100 ? v : (Fail(field), 0.0);
  }
  // A σ: unknown (NaN) or finite and not negative.
  // A σ: unknown (NaN), not determined (+inf, e.g. the rotation of a slave whose motions are
  // all parallel), or within the physical bounds.
  double Sigma(const char* field) {
    const double v = Number(field);
    return std::isnan(v) || v == std::numeric_limits<double>::infinity() || (v >= 0.0 && v <= 1e100)
               ? v
               : (Fail(field), 0.0);
  }
  int64_t Integer(const char* field, int64_t lo, int64_t hi) {
    int64_t v = 0;
    if (!ok_ || !(in_ >> v) || v < lo || v > hi) return Fail(field), 0;
    return v;
  }
  int Count(const char* field) { return static_cast<int>(Integer(field, 0, 1'000'000'000)); }
  std::string Text(const char* label) {
    if (!Word(label)) return {};
    const int64_t n = Integer(label, 0, 1 << 20);
    if (!ok_ || in_.get() != ' ') return Fail(label), std::string();
    std::string text(static_cast<size_t>(n), '\0');
    if (!in_.read(text.data(), n)) return Fail(label), std::string();
    return text;
  }
  template <typename Derived>
  void Finite(const char* field, Eigen::DenseBase<Derived>& m) {
    for (Eigen::Index i = 0; i < m.size(); ++i) m.derived().data()[i] = Finite(field);
  }
  void Reject(const char* field) { Fail(field); }
  bool ok() const { return ok_; }
  const std::string& failed() const { return failed_; }

 private:
  bool Fail(const char* field) {
    if (ok_) failed_ = field;
    ok_ = false;
    return false;
  }
  std::istringstream in_;
  bool ok_ = true;
  std::string failed_;
};

Eigen::Quaterniond UnitQuaternion(Tokens& t, const char* field) {
  Eigen::Vector4d wxyz;
  t.Finite(field, wxyz);
  if (t.ok() && std::abs(wxyz.norm() - 1.0) > 1e-6) t.Reject(field);
  return Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
}

void ReadObservability(Tokens& t, Observability* o) {
  t.Word("observability");
  t.Finite("observability", o->rotation_eigenvalues);
  double* fields[] = {&o->rotation_weak_std_deg,
                      &o->position_min_eigenvalue,
                      &o->axis_spread_deg,
                      &o->slave_axis_spread_deg,
                      &o->tilt_snr,
                      &o->axis_std_ratio,
                      &o->max_rotation_deg,
                      &o->rotation_noise_deg,
                      &o->translational_below_deg};
  for (double* f : fields) *f = t.Number("observability");
  o->planar = t.Integer("observability planar", 0, 1) == 1;
  t.Finite("observability axis", o->planar_axis);
}

void ReadCalibration(Tokens& t, SlaveCalibration* c) {
  t.Word("calibration");
  c->name = t.Text("name");
  c->pairs = t.Text("pairs");
  c->message = t.Text("message");
  c->contradiction = t.Text("contradiction");
  t.Word("kind");
  c->termination = static_cast<Termination>(t.Integer("termination", 0, 4));
  c->state = static_cast<SlaveState>(t.Integer("state", 0, 3));
  c->motion_model = static_cast<MotionModel>(t.Integer("motion model", 1, 3));
  c->scale_model = static_cast<ScaleModel>(t.Integer("scale model", 1, 3));
  t.Word("estimate");
  c->estimate.q = UnitQuaternion(t, "estimate q");
  t.Finite("estimate C", c->estimate.C);
  c->estimate.scale = t.Finite("estimate scale");
  t.Word("std");
  c->rot_std_deg = t.Sigma("std rotation");
  for (int i = 0; i < 3; ++i) c->pos_std[i] = t.Sigma("std C");
  c->axis_offset_std = t.Sigma("std axis");
  t.Word("observable");
  c->position_observable = t.Integer("observable", 0, 1) == 1;
  c->unobservable_from_prior = t.Integer("observable prior", 0, 1) == 1;
  c->unobservable.resize(static_cast<size_t>(t.Integer("unobservable", 0, 3)));
  for (Eigen::Vector3d& u : c->unobservable) t.Finite("unobservable", u);
  t.Word("scales");
  c->scales.resize(static_cast<size_t>(t.Integer("scales", 0, 1'000'000)));
  for (SegmentScale& s : c->scales) {
    t.Word("scale");
    s.segment = static_cast<int>(t.Integer("scale segment", INT32_MIN, INT32_MAX));
    s.scale = t.Finite("scale");
    s.std = t.Sigma("scale std");
    s.measured_mean = t.Number("scale measured mean");
    s.measured_std = t.Number("scale measured std");
    s.measured_count = t.Count("scale measured count");
  }
  t.Word("motions");
  MotionCounts& m = c->motions;
  for (int* f : {&m.total, &m.used, &m.small_rotation, &m.angle_mismatch, &m.residual_outlier}) {
    *f = t.Count("motions");
  }
  t.Word("glitches");
  GlitchCounts& g = c->glitches;
  for (int* f :
       {&g.position_jump, &g.rotation_jump, &g.angle_mismatch, &g.in_master, &g.in_slave}) {
    *f = t.Count("glitches");
  }
  ReadObservability(t, &c->observability);
  t.Word("time_offset");
  c->time_offset_s = t.Number("time_offset");
  c->time_offset_std_s = t.Sigma("time_offset std");
}

void ReadInflation(Tokens& t, SlavePublishedState* s) {
  t.Word("drift");
  s->consecutive_angle_var.value = t.Finite("drift");
  s->consecutive_angle_var.count = t.Count("drift");
  s->pair_span.value = t.Finite("drift");
  s->pair_span.count = t.Count("drift");
  t.Word("forget");
  s->log_decay = t.Finite("forget");
  s->last_decay_ns = t.Integer("forget", -1, INT64_MAX);
  t.Word("convergence");
  s->stable = t.Count("convergence");
  s->last_q = UnitQuaternion(t, "convergence q");
  t.Word("glitches");
  GlitchCounts& g = s->glitches;
  for (int* f :
       {&g.position_jump, &g.rotation_jump, &g.angle_mismatch, &g.in_master, &g.in_slave}) {
    *f = t.Count("glitches");
  }
  t.Word("blocks");
  s->block_ns = t.Integer("blocks", 0, INT64_MAX);
  s->blocks.resize(static_cast<size_t>(t.Integer("blocks", 0, 100'000)));
  for (RotationBlockState& b : s->blocks) {
    t.Word("block");
    b.start_ns = t.Integer("block start", INT64_MIN, INT64_MAX);
    b.weight = t.Finite("block weight");
    t.Finite("block", b.ata);
  }
}

}  // namespace

void WritePublished(std::ostream& out, const SlavePublishedState& s) {
  const SlaveOnlineState& o = s.online;
  out << "published\nonline " << o.flags << ' ' << o.segment << ' ' << o.last_update_ns << ' '
      << o.short_long_rot_deg << ' ' << o.keyframes << ' ' << o.gated_scale << ' '
      << o.decalibration_events << "\ndecalibration " << s.decalibration.disagreements << ' '
      << s.decalibration.disagree_since_ns << ' ' << s.decalibration.decalibrated_at_ns
      << "\ndrift " << s.consecutive_angle_var.value << ' ' << s.consecutive_angle_var.count << ' '
      << s.pair_span.value << ' ' << s.pair_span.count << "\nforget " << s.log_decay << ' '
      << s.last_decay_ns << "\nconvergence " << s.stable << ' ' << s.last_q.w() << ' '
      << s.last_q.x() << ' ' << s.last_q.y() << ' ' << s.last_q.z() << "\nglitches "
      << s.glitches.position_jump << ' ' << s.glitches.rotation_jump << ' '
      << s.glitches.angle_mismatch << ' ' << s.glitches.in_master << ' ' << s.glitches.in_slave
      << "\nblocks " << s.block_ns << ' ' << s.blocks.size() << '\n';
  for (const RotationBlockState& b : s.blocks) {
    out << "block " << b.start_ns << ' ' << b.weight;
    WriteNumbers(out, b.ata);
    out << '\n';
  }
  WriteCalibration(out, s.published);
  out << "refined " << (s.refined ? 1 : 0) << ' ' << (s.refined_from_history ? 1 : 0) << '\n';
  if (s.refined) WriteCalibration(out, *s.refined);
  out << "end\n";
}

Status ReadPublished(std::string_view text, int version, SlavePublishedState* out) {
  Tokens t(text);
  SlavePublishedState s;
  t.Word("published");
  t.Word("online");
  SlaveOnlineState& o = s.online;
  o.flags = static_cast<uint32_t>(t.Integer("online flags", 0, UINT32_MAX));
  o.segment = static_cast<int>(t.Integer("online segment", INT32_MIN, INT32_MAX));
  o.last_update_ns = t.Integer("online last update", INT64_MIN, INT64_MAX);
  o.short_long_rot_deg = t.Finite("online short/long rotation");
  o.keyframes = t.Count("online keyframes");
  o.gated_scale = t.Count("online gated scale");
  o.decalibration_events = t.Count("online decalibrations");
  if (version >= 7) {
    t.Word("decalibration");
    s.decalibration.disagreements = t.Count("decalibration disagreements");
    s.decalibration.disagree_since_ns = t.Integer("decalibration since", -1, INT64_MAX);
    s.decalibration.decalibrated_at_ns = t.Integer("decalibration at", -1, INT64_MAX);
  }
  ReadInflation(t, &s);
  ReadCalibration(t, &s.published);
  t.Word("refined");
  const bool refined = t.Integer("refined", 0, 1) == 1;
  s.refined_from_history = t.Integer("refined from history", 0, 1) == 1;
  if (refined) ReadCalibration(t, &s.refined.emplace());
  t.Word("end");
  if (!t.ok()) return Error{"malformed or out of range published estimate: " + t.failed()};
  s.present = true;
  *out = std::move(s);
  return Status::Ok();
}

}  // namespace rigcal::io::internal
