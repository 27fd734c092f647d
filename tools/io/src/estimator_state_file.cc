// SPDX-License-Identifier: Apache-2.0
// Reading and writing the estimator state file (estimator_state_file.h).
#include "rigcal/io/estimator_state_file.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <sstream>

#include "estimator_state_published.h"
#include "estimator_state_ranges.h"

namespace rigcal::io {
namespace {

constexpr const char* kMagic = "rigcal-estimator-state";

// Where the last "checksum " in `text` starts (as text.rfind("checksum ")), npos when nowhere.
// rfind compares the word at every position from the end, each a memcmp call: under ASan an
// intercepted call per byte of the file, most of the time the state fuzz target spent on a long
// input. This compares only where a 'c' is.
size_t LastChecksumWord(std::string_view text) {
  constexpr std::string_view kWord = "checksum ";
  for (size_t pos = text.rfind('c'); pos != std::string_view::npos;
       pos = pos == 0 ? std::string_view::npos : text.rfind('c', pos - 1)) {
    if (text.substr(pos, kWord.size()) == kWord) return pos;
  }
  return std::string_view::npos;
}

uint64_t Fnv1a(std::string_view s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// A matrix as "<label> v0 v1 ...\n", column-major.
template <typename Derived>
void Write(std::ostream& out, const char* label, const Eigen::MatrixBase<Derived>& m) {
  out << label;
  for (Eigen::Index i = 0; i < m.size(); ++i) out << ' ' << m.derived().data()[i];
  out << '\n';
}

template <typename Derived>
bool Read(std::istream& in, const char* label, Eigen::MatrixBase<Derived>& m) {
  std::string word;
  if (!(in >> word) || word != label) return false;
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    if (!(in >> m.derived().data()[i]) || !std::isfinite(m.derived().data()[i])) return false;
  }
  return true;
}

bool ReadScalar(std::istream& in, const char* label, double* v) {
  std::string word;
  return (in >> word) && word == label && (in >> *v) && std::isfinite(*v);
}

void WriteSums(std::ostream& out, const MotionSums& s) {
  Write(out, "M", s.rotation);
  Write(out, "v00", s.planar.v00);
  Write(out, "vii", s.planar.vii);
  Write(out, "v0i", s.planar.v0i);
  Write(out, "K", s.planar.k);
  Write(out, "c0c0", s.planar.c0c0);
  Write(out, "Hplmarg", s.planar.h_marg);
  Write(out, "gplmarg", s.planar.g_marg);
  out << "cplmarg " << s.planar.c_marg << '\n';
  Write(out, "Hcc", s.h_cc);
  Write(out, "gc", s.g_c);
  out << "c0sq " << s.c0_sq << '\n';
  Write(out, "Sdir", s.s_dir);
  Write(out, "Ddir", s.d_dir);
  Write(out, "Hmarg", s.h_marg);
  Write(out, "gmarg", s.g_marg);
  out << "c0sqmarg " << s.c0_sq_marg << '\n';
  out << "weight " << s.weight << "\nposweight " << s.position_weight.value_or(s.weight)
      << "\nmaxrot " << s.max_rotation << "\nmotions " << s.motions << '\n';
  out << "segments " << s.segments.size() << '\n';
  for (const auto& [id, seg] : s.segments) {
    out << "segment " << id << '\n';
    Write(out, "P", seg.P);
    Write(out, "Q", seg.Q);
    Write(out, "N", seg.N);
    out << "n " << seg.n << "\nlc " << seg.len_cross << "\nls " << seg.len_sq << "\nw "
        << seg.weight << "\nscale " << seg.last_scale << '\n';
  }
  out << "closed " << s.closed_scales.size() << '\n';
  for (const auto& [id, v] : s.closed_scales) out << id << ' ' << v << '\n';
}

// The sums written by WriteSums; false on a malformed text. "Ddir" follows "Sdir" since state
// version 3; a version-2 text goes on with "Hmarg" and the moments are derived. "posweight"
// follows "weight" since version 8; before, the position sums' weight is unknown (none).
bool ReadSums(const std::string& text, int version, MotionSums* out) {
  std::istringstream in(text);
  MotionSums s;
  const bool has_d = text.find("\nDdir ") != std::string::npos;
  double motions = 0.0, count = 0.0;
  if (!Read(in, "M", s.rotation) || !Read(in, "v00", s.planar.v00) ||
      !Read(in, "vii", s.planar.vii) || !Read(in, "v0i", s.planar.v0i) ||
      !Read(in, "K", s.planar.k) || !Read(in, "c0c0", s.planar.c0c0) ||
      !Read(in, "Hplmarg", s.planar.h_marg) || !Read(in, "gplmarg", s.planar.g_marg) ||
      !ReadScalar(in, "cplmarg", &s.planar.c_marg) || !Read(in, "Hcc", s.h_cc) ||
      !Read(in, "gc", s.g_c) || !ReadScalar(in, "c0sq", &s.c0_sq) || !Read(in, "Sdir", s.s_dir) ||
      (has_d && !Read(in, "Ddir", s.d_dir)) || !Read(in, "Hmarg", s.h_marg) ||
      !Read(in, "gmarg", s.g_marg) || !ReadScalar(in, "c0sqmarg", &s.c0_sq_marg) ||
      !ReadScalar(in, "weight", &s.weight) ||
      (version >= 8 && !ReadScalar(in, "posweight", &s.position_weight.emplace())) ||
      !ReadScalar(in, "maxrot", &s.max_rotation) || !ReadScalar(in, "motions", &motions) ||
      !ReadScalar(in, "segments", &count)) {
    return false;
  }
  if (!has_d) s.d_dir = DirectionMomentsFromCrossMoments(s.s_dir, s.weight);
  s.motions = static_cast<int>(motions);
  if (count < 0 || count > 1e6) return false;
  for (int k = 0; k < static_cast<int>(count); ++k) {
    double id = 0.0;
    SegmentSums seg;
    if (!ReadScalar(in, "segment", &id) || !Read(in, "P", seg.P) || !Read(in, "Q", seg.Q) ||
        !Read(in, "N", seg.N) || !ReadScalar(in, "n", &seg.n) ||
        !ReadScalar(in, "lc", &seg.len_cross) || !ReadScalar(in, "ls", &seg.len_sq) ||
        !ReadScalar(in, "w", &seg.weight) || !ReadScalar(in, "scale", &seg.last_scale)) {
      return false;
    }
    s.segments[static_cast<int>(id)] = seg;
  }
  if (!ReadScalar(in, "closed", &count) || count < 0 || count > 1e6) return false;
  for (int k = 0; k < static_cast<int>(count); ++k) {
    int id = 0;
    double v = 0.0;
    if (!(in >> id >> v) || !std::isfinite(v)) return false;
    s.closed_scales[id] = v;
  }
  *out = std::move(s);
  return true;
}

// Reads the slave blocks that follow the master_segment line (`rest`), one per slave camera.
Status ReadSlaves(std::string rest, int version, RigEstimatorState* state) {
  const std::vector<std::string>& names = state->cameras;
  for (size_t i = 0; i + 1 < names.size(); ++i) {
    const std::string& name = names[i + 1];
    SlaveEstimatorState& s = state->slaves.emplace_back();
    std::istringstream sin(rest);
    std::string word;
    size_t idx = 0;
    if (!(sin >> word >> idx) || word != "slave" || idx != i) {
      return Error{"malformed slave block"};
    }
    MotionCounts& c = s.counts;
    if (!(sin >> word >> c.total >> c.used >> c.small_rotation >> c.angle_mismatch >>
          c.residual_outlier) ||
        word != "counts") {
      return Error{"malformed counts of slave " + name};
    }
    if (!(sin >> word >> s.angle_var.value >> s.angle_var.count >> s.rot_var.value >>
          s.rot_var.count >> s.pos_var.value >> s.pos_var.count >> s.ci_sq.value >>
          s.ci_sq.count) ||
        word != "noise") {
      return Error{"malformed noise of slave " + name};
    }
    if (!(sin >> word >> s.segment) || word != "segment") return Error{"malformed segment"};
    int rotating = 0, general_model = 0;
    if (!(sin >> word >> rotating >> general_model) || word != "model") {
      return Error{"malformed model of slave " + name};
    }
    s.rotating = rotating != 0;
    s.general_model = general_model != 0;
    const std::string remaining((std::istreambuf_iterator<char>(sin)),
                                std::istreambuf_iterator<char>());
    const size_t long_pos = remaining.find("long\n");
    const size_t short_pos = remaining.find("short\n");
    if (long_pos == std::string::npos || short_pos == std::string::npos) {
      return Error{"malformed statistics of slave " + name};
    }
    const size_t next = remaining.find("\nslave ", short_pos);
    const std::string long_text = remaining.substr(long_pos + 5, short_pos - long_pos - 5);
    std::string short_text = remaining.substr(
        short_pos + 6, next == std::string::npos ? std::string::npos : next + 1 - short_pos - 6);
    // Version 6: the published estimate follows the short statistics.
    const size_t published = short_text.find("\npublished\n");
    const std::string published_text =
        published == std::string::npos ? std::string() : short_text.substr(published + 1);
    if (published != std::string::npos) short_text.resize(published + 1);
    if (!ReadSums(long_text, version, &s.long_stats) ||
        !ReadSums(short_text, version, &s.short_stats)) {
      return Error{"malformed statistics of slave " + name};
    }
    if (!published_text.empty()) {
      if (const Status read = internal::ReadPublished(published_text, version, &s.resume);
          !read.ok()) {
        return Error{"slave " + name + ": " + read.message()};
      }
    }
    rest = next == std::string::npos ? "" : remaining.substr(next + 1);
  }
  return Status::Ok();
}

// Version 5: "clocks <n>" and n "clock" lines, n 0 or one per slave.
Status ReadClockOffsets(std::istream& b, RigEstimatorState* state) {
  std::string word;
  size_t n = 0;
  const size_t slaves = state->cameras.empty() ? 0 : state->cameras.size() - 1;
  if (!(b >> word >> n) || word != "clocks" || (n != 0 && n != slaves)) {
    return Error{"malformed clock offsets (none, or one per slave)"};
  }
  for (size_t i = 0; i < n; ++i) {
    ClockOffsetState c;
    size_t index = 0;
    int initialised = 0;
    double p01 = 0.0;
    if (!(b >> word >> index >> initialised >> c.offset_s >> c.drift >> c.covariance(0, 0) >> p01 >>
          c.covariance(1, 1) >> c.t_ns >> c.measurements >> c.jumps) ||
        word != "clock" || index != i || (initialised != 0 && initialised != 1)) {
      return Error{"malformed clock offset of slave " + std::to_string(i)};
    }
    c.initialised = initialised == 1;
    c.covariance(0, 1) = c.covariance(1, 0) = p01;
    state->clock_offsets.push_back(c);
  }
  return Status::Ok();
}

// Version 6: "fingerprints <n>" and n lines "fingerprint <camera> <t_ns> <q wxyz> <C>" of the
// first then "... " of the newest pose taken, n 0 or one per camera.
void WriteFingerprints(std::ostream& out, const RigEstimatorState& state) {
  const size_t n = state.first_consumed.size() == state.cameras.size() &&
                           state.last_consumed.size() == state.cameras.size()
                       ? state.cameras.size()
                       : 0;
  out << "fingerprints " << n << '\n';
  for (size_t c = 0; c < n; ++c) {
    out << "fingerprint " << c;
    for (const PoseFingerprint* f : {&state.first_consumed[c], &state.last_consumed[c]}) {
      out << ' ' << f->t_ns << ' ' << f->q.w() << ' ' << f->q.x() << ' ' << f->q.y() << ' '
          << f->q.z() << ' ' << f->C.x() << ' ' << f->C.y() << ' ' << f->C.z();
    }
    out << '\n';
  }
}

Status ReadFingerprints(std::istream& b, RigEstimatorState* state) {
  std::string word;
  size_t n = 0;
  if (!(b >> word >> n) || word != "fingerprints" || (n != 0 && n != state->cameras.size())) {
    return Error{"malformed pose fingerprints (none, or one per camera)"};
  }
  for (size_t c = 0; c < n; ++c) {
    size_t index = 0;
    if (!(b >> word >> index) || word != "fingerprint" || index != c) {
      return Error{"malformed pose fingerprint of camera " + std::to_string(c)};
    }
    for (auto* list : {&state->first_consumed, &state->last_consumed}) {
      PoseFingerprint f;
      double w = 0, x = 0, y = 0, z = 0;
      if (!(b >> f.t_ns >> w >> x >> y >> z >> f.C.x() >> f.C.y() >> f.C.z()) || f.t_ns < -1 ||
          !f.C.allFinite() || !std::isfinite(w + x + y + z)) {
        return Error{"malformed pose fingerprint of camera '" + state->cameras[c] + "'"};
      }
      f.q = Eigen::Quaterniond(w, x, y, z);
      list->push_back(f);
    }
  }
  return Status::Ok();
}

}  // namespace

std::string FormatEstimatorState(const RigEstimatorState& state) {
  std::ostringstream body;
  body.precision(17);
  body << "cameras " << state.cameras.size();
  for (const auto& n : state.cameras) body << ' ' << n;
  body << "\nmaster_segment " << state.master_segment << ' ' << (state.have_master_segment ? 1 : 0)
       << '\n';
  body << "consumed " << state.consumed_t_ns.size();
  for (const int64_t t : state.consumed_t_ns) body << ' ' << t;
  body << "\nclocks " << state.clock_offsets.size() << '\n';
  for (size_t i = 0; i < state.clock_offsets.size(); ++i) {
    const ClockOffsetState& c = state.clock_offsets[i];
    body << "clock " << i << ' ' << (c.initialised ? 1 : 0) << ' ' << c.offset_s << ' ' << c.drift
         << ' ' << c.covariance(0, 0) << ' ' << c.covariance(0, 1) << ' ' << c.covariance(1, 1)
         << ' ' << c.t_ns << ' ' << c.measurements << ' ' << c.jumps << '\n';
  }
  WriteFingerprints(body, state);
  for (size_t i = 0; i < state.slaves.size(); ++i) {
    const SlaveEstimatorState& s = state.slaves[i];
    const MotionCounts& c = s.counts;
    body << "slave " << i << "\ncounts " << c.total << ' ' << c.used << ' ' << c.small_rotation
         << ' ' << c.angle_mismatch << ' ' << c.residual_outlier << "\nnoise " << s.angle_var.value
         << ' ' << s.angle_var.count << ' ' << s.rot_var.value << ' ' << s.rot_var.count << ' '
         << s.pos_var.value << ' ' << s.pos_var.count << ' ' << s.ci_sq.value << ' '
         << s.ci_sq.count << "\nsegment " << s.segment << "\nmodel " << (s.rotating ? 1 : 0) << ' '
         << (s.general_model ? 1 : 0) << "\nlong\n";
    WriteSums(body, s.long_stats);
    body << "short\n";
    WriteSums(body, s.short_stats);
    if (s.resume.present) internal::WritePublished(body, s.resume);
  }
  const std::string text = body.str();
  std::ostringstream out;
  out << kMagic << ' ' << kEstimatorStateVersion << '\n'
      << text << "checksum " << std::hex << Fnv1a(text) << '\n';
  return out.str();
}

std::string WithEstimatorStateChecksum(std::string_view text) {
  const size_t body_start = std::min(text.size(), text.find('\n') + 1);
  size_t sum_pos = LastChecksumWord(text);
  if (sum_pos == std::string_view::npos || sum_pos < body_start) sum_pos = text.size();
  std::ostringstream out;
  out << text.substr(0, sum_pos) << "checksum " << std::hex
      << Fnv1a(text.substr(body_start, sum_pos - body_start)) << '\n';
  return out.str();
}

Expected<RigEstimatorState> ParseEstimatorState(std::string_view view) {
  const std::string text(view);
  std::istringstream in(text);
  std::string magic;
  int version = 0;
  if (!(in >> magic >> version) || magic != kMagic) {
    return Error{"not a rigcal estimator state (bad header)"};
  }
  if (version < kOldestEstimatorStateVersion || version > kEstimatorStateVersion) {
    return Error{"state version " + std::to_string(version) + ", this build reads versions " +
                 std::to_string(kOldestEstimatorStateVersion) + " to " +
                 std::to_string(kEstimatorStateVersion)};
  }
  const size_t body_start = text.find('\n') + 1;
  const size_t sum_pos = LastChecksumWord(text);
  if (sum_pos == std::string::npos || sum_pos < body_start) return Error{"missing checksum"};
  const std::string body = text.substr(body_start, sum_pos - body_start);
  std::istringstream sum_in(text.substr(sum_pos + 9));
  uint64_t stored = 0;
  if (!(sum_in >> std::hex >> stored) || stored != Fnv1a(body)) {
    return Error{"checksum mismatch (file corrupt or truncated)"};
  }
  // The checksum line ends the file: anything after it is not covered by the checksum.
  const std::string after((std::istreambuf_iterator<char>(sum_in)),
                          std::istreambuf_iterator<char>());
  if (const size_t garbage = after.find_first_not_of(" \t\r\n"); garbage != std::string::npos) {
    const size_t at = text.size() - after.size() + garbage;
    const auto line =
        1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    return Error{"line " + std::to_string(line) + ": text after the checksum line"};
  }
  RigEstimatorState state;
  std::istringstream b(body);
  std::string word;
  size_t count = 0;
  if (!(b >> word >> count) || word != "cameras") return Error{"malformed camera list"};
  for (size_t i = 0; i < count; ++i) {
    if (!(b >> word)) return Error{"malformed camera list"};
    state.cameras.push_back(word);
  }
  int have = 0;
  if (!(b >> word >> state.master_segment >> have) || word != "master_segment") {
    return Error{"malformed master_segment"};
  }
  state.have_master_segment = have != 0;
  if (version >= 4) {
    // How far each camera's input was consumed: one stamp per camera, -1 for none.
    size_t n = 0;
    if (!(b >> word >> n) || word != "consumed" || (n != 0 && n != count)) {
      return Error{"malformed consumed stamps (one per camera)"};
    }
    for (size_t i = 0; i < n; ++i) {
      int64_t t = 0;
      if (!(b >> t) || t < -1) {
        return Error{"consumed stamp of camera '" + state.cameras[i] +
                     "' is malformed or out of range [-1, 2^63)"};
      }
      state.consumed_t_ns.push_back(t);
    }
  }
  if (version >= 5) {
    if (const Status read = ReadClockOffsets(b, &state); !read.ok()) return read;
  }
  if (version >= 6) {
    if (const Status read = ReadFingerprints(b, &state); !read.ok()) return read;
  }
  const std::string rest((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
  if (const Status read = ReadSlaves(rest, version, &state); !read.ok()) return read;
  if (const Status ranges = CheckEstimatorStateRanges(state); !ranges.ok()) return ranges;
  return state;
}

}  // namespace rigcal::io
