#include "rigcal/lcm/lcm_messages.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <exception>
#include <set>
#include <sstream>
#include <utility>

namespace rigcal::tools {
namespace {

constexpr int kHashBytes = 8;

std::string FormatNumber(double value) {
  std::ostringstream out;
  out.precision(10);
  out << value;
  return out.str();
}

// Collects the first failed rule of one message. Fields are named "<prefix>.<field>".
class Checker {
 public:
  Checker(std::string_view channel, std::string prefix)
      : channel_(channel), prefix_(std::move(prefix)) {}

  bool ok() const { return !rejection_.has_value(); }
  std::optional<Rejection> TakeRejection() { return std::move(rejection_); }

  // A checker for a nested message, e.g. "rig_extrinsics_t.slaves[1]".
  Checker Nested(const std::string& field) const { return Checker(channel_, Field(field)); }
  void Merge(Checker&& nested) {
    if (ok() && !nested.ok()) rejection_ = nested.TakeRejection();
  }

  void Fail(RejectCause cause, std::string_view field, const std::string& what) {
    if (!ok()) return;
    rejection_ = Rejection{cause, std::string(channel_) + ": " + Field(field) + ": " + what + " (" +
                                      ToString(cause) + ")"};
  }

  void Version(int16_t version, int16_t expected) {
    if (version != expected) {
      Fail(RejectCause::kWrongVersion, "version",
           "schema version " + std::to_string(version) + ", this build reads " +
               std::to_string(expected));
    }
  }

  void Finite(std::string_view field, const double* values, int count) {
    for (int i = 0; i < count; ++i) {
      if (!std::isfinite(values[i])) {
        const std::string name =
            count == 1 ? std::string(field) : std::string(field) + "[" + std::to_string(i) + "]";
        Fail(RejectCause::kNonFinite, name, "not finite (" + FormatNumber(values[i]) + ")");
        return;
      }
    }
  }
  void Finite(std::string_view field, double value) { Finite(field, &value, 1); }

  // A unit vector within kUnitTolerance, normalised in place; `cause` for a wrong norm.
  void Unit(std::string_view field, double* values, int count, RejectCause cause,
            std::string_view what) {
    Finite(field, values, count);
    if (!ok()) return;
    double norm_sq = 0.0;
    for (int i = 0; i < count; ++i) norm_sq += values[i] * values[i];
    const double norm = std::sqrt(norm_sq);
    if (!(std::abs(norm - 1.0) <= kUnitTolerance)) {
      Fail(cause, field,
           "|" + std::string(what) + "| = " + FormatNumber(norm) + " is not 1 within " +
               FormatNumber(kUnitTolerance));
      return;
    }
    for (int i = 0; i < count; ++i) values[i] /= norm;
  }
  void Quaternion(std::string_view field, double* q) {
    Unit(field, q, 4, RejectCause::kNonUnitQuaternion, "q");
  }

  // Range checks; `value` is a double or an integer.
  template <typename T>
  void AtLeast(std::string_view field, T value, T min) {
    if (!(value >= min)) {
      Fail(RejectCause::kOutOfRange, field,
           FormatNumber(static_cast<double>(value)) + " is below " +
               FormatNumber(static_cast<double>(min)));
    }
  }
  template <typename T>
  void InRange(std::string_view field, T value, T min, T max) {
    if (!(value >= min && value <= max)) {
      Fail(RejectCause::kOutOfRange, field,
           FormatNumber(static_cast<double>(value)) + " is outside [" +
               FormatNumber(static_cast<double>(min)) + ", " +
               FormatNumber(static_cast<double>(max)) + "]");
    }
  }

  // Array length field `count_field` against the vector's size.
  void Count(std::string_view count_field, int64_t count, size_t vector_size,
             std::string_view vector_field) {
    if (count < 0) {
      Fail(RejectCause::kBadSize, count_field, "negative length " + std::to_string(count));
    } else if (static_cast<uint64_t>(count) != vector_size) {
      Fail(RejectCause::kBadSize, count_field,
           std::to_string(count) + " but " + std::string(vector_field) + " has " +
               std::to_string(vector_size) + " elements");
    }
  }

  // A camera name: non-empty, no NUL, and one of names[first..] unless `names` is empty (no
  // table: any name). `allowed_what` says which names ("the rig's cameras", "the rig's slaves").
  void CameraName(std::string_view field, const std::string& name, const CameraNames& names,
                  size_t first, std::string_view allowed_what) {
    if (name.empty()) {
      Fail(RejectCause::kUnknownCamera, field, "empty camera name");
    } else if (name.find('\0') != std::string::npos) {
      Fail(RejectCause::kMalformed, field, "camera name contains a NUL byte");
    } else if (!names.empty() && std::find(names.begin() + std::min(first, names.size()),
                                           names.end(), name) == names.end()) {
      Fail(RejectCause::kUnknownCamera, field,
           "camera '" + name + "' is not one of " + std::string(allowed_what));
    }
  }

 private:
  std::string Field(std::string_view field) const { return prefix_ + "." + std::string(field); }

  std::string channel_;
  std::string prefix_;
  std::optional<Rejection> rejection_;
};

void CheckSlave(const CameraNames& names, slave_extrinsics_t* s, Checker* check) {
  check->CameraName("name", s->name, names, 1, "the rig's slaves");
  check->Quaternion("q", s->q);
  check->Finite("C", s->C, 3);
  check->Finite("scale", s->scale);
  check->Finite("rot_std_deg", s->rot_std_deg);
  check->Finite("pos_std", s->pos_std, 3);
  check->Finite("scale_std", s->scale_std);
  check->Finite("rotation_eigen_gap", s->rotation_eigen_gap);
  check->Finite("position_min_eigenvalue", s->position_min_eigenvalue);
  check->Finite("axis_spread_deg", s->axis_spread_deg);
  check->Finite("planar_axis", s->planar_axis, 3);
  check->Finite("axis_offset_std", s->axis_offset_std);

  const bool converged = (s->flags & kFlagConverged) != 0;
  const bool initialising = (s->flags & kFlagInitialising) != 0;
  if ((s->flags & ~kKnownFlags) != 0) {
    check->Fail(RejectCause::kOutOfRange, "flags",
                "undefined bits " + std::to_string(s->flags & ~kKnownFlags));
  } else if (converged == initialising) {
    check->Fail(RejectCause::kOutOfRange, "flags",
                "exactly one of FLAG_INITIALISING and FLAG_CONVERGED must be set");
  }
  if (converged && !(s->scale > 0.0)) {
    check->Fail(RejectCause::kOutOfRange, "scale",
                FormatNumber(s->scale) + " is not positive in a converged estimate");
  }
  check->AtLeast<int32_t>("segment", s->segment, 0);
  check->AtLeast("rot_std_deg", s->rot_std_deg, 0.0);
  for (int i = 0; i < 3; ++i) {
    check->AtLeast("pos_std[" + std::to_string(i) + "]", s->pos_std[i], 0.0);
  }
  check->AtLeast("scale_std", s->scale_std, 0.0);
  check->AtLeast<int32_t>("motions_used", s->motions_used, 0);
  check->AtLeast<int32_t>("motions_rejected", s->motions_rejected, 0);
  check->AtLeast("rotation_eigen_gap", s->rotation_eigen_gap, 0.0);
  check->InRange("axis_spread_deg", s->axis_spread_deg, 0.0, 180.0);
  if (s->flags & kFlagPlanar) {
    check->Unit("planar_axis", s->planar_axis, 3, RejectCause::kOutOfRange, "planar_axis");
  }
  if ((s->flags & kFlagAxisFromPrior) && !(s->flags & kFlagPlanar)) {
    check->Fail(RejectCause::kOutOfRange, "flags",
                "FLAG_AXIS_FROM_PRIOR without FLAG_PLANAR_UNOBSERVABLE_AXIS");
  }
  if (s->axis_offset_std != -1.0) check->AtLeast("axis_offset_std", s->axis_offset_std, 0.0);
}

void CheckCameraStatus(const CameraNames& names, camera_status_t* c, Checker* check) {
  check->CameraName("name", c->name, names, 0, "the rig's cameras");
  check->Finite("fps", c->fps);
  check->AtLeast("fps", c->fps, 0.0);
  const std::pair<const char*, int64_t> counters[] = {
      {"frames_received", c->frames_received},
      {"dropped_late", c->dropped_late},
      {"dropped_duplicate", c->dropped_duplicate},
      {"dropped_out_of_order", c->dropped_out_of_order},
      {"dropped_overflow", c->dropped_overflow},
      {"dropped_never_matched", c->dropped_never_matched},
      {"dropped_invalid", c->dropped_invalid}};
  for (const auto& [field, value] : counters) check->AtLeast<int64_t>(field, value, 0);
  check->InRange<int8_t>("vo_state", c->vo_state, camera_status_t::VO_INITIALISING,
                         camera_status_t::VO_DEAD);
  check->AtLeast<int64_t>("last_pose_age_ms", c->last_pose_age_ms, -1);
}

// Bytes per pixel of the raw pixel formats this project writes; 0 when unknown.
int BytesPerPixel(const std::string& fourcc) {
  if (fourcc == "GREY") return 1;
  if (fourcc == "Y16 " || fourcc == "YUYV") return 2;
  if (fourcc == "RGB3" || fourcc == "BGR3") return 3;
  return 0;
}

// ---- Layout walk before LCM decodes: every array length must fit in the buffer ----

// Reads LCM's big-endian wire format without trusting it.
class Cursor {
 public:
  Cursor(const uint8_t* data, int64_t size) : data_(data), size_(size) {}
  int64_t remaining() const { return size_ - pos_; }
  bool Skip(int64_t bytes) {
    if (remaining() < bytes) return false;
    pos_ += bytes;
    return true;
  }
  bool ReadInt32(int32_t* value) {
    if (remaining() < 4) return false;
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v = (v << 8) | data_[pos_ + i];
    *value = static_cast<int32_t>(v);
    pos_ += 4;
    return true;
  }

 private:
  const uint8_t* data_;
  int64_t size_;
  int64_t pos_ = kHashBytes;  // the fingerprint is checked separately
};

// Steps through the fields that precede an array length. The first failure is kept.
class LayoutWalk {
 public:
  LayoutWalk(const uint8_t* data, int64_t size, Checker* check)
      : cursor_(data, size), check_(check) {}
  void Fixed(std::string_view field, int64_t bytes) {
    if (check_->ok() && !cursor_.Skip(bytes)) Truncated(field);
  }
  void String(std::string_view field) {
    int32_t length = 0;
    if (!check_->ok()) return;
    if (!cursor_.ReadInt32(&length)) return Truncated(field);
    if (length < 1) {
      return check_->Fail(RejectCause::kMalformed, field,
                          "string length " + std::to_string(length) + " (< 1)");
    }
    if (!cursor_.Skip(length)) Truncated(field);
  }
  // An array length, and the least number of bytes each element takes.
  void Count(std::string_view field, int64_t min_element_bytes) {
    int32_t count = 0;
    if (!check_->ok()) return;
    if (!cursor_.ReadInt32(&count)) return Truncated(field);
    if (count < 0) {
      return check_->Fail(RejectCause::kBadSize, field, "negative length " + std::to_string(count));
    }
    if (count * min_element_bytes > cursor_.remaining()) {
      check_->Fail(RejectCause::kTruncated, field,
                   std::to_string(count) + " elements need at least " +
                       std::to_string(count * min_element_bytes) + " bytes, " +
                       std::to_string(cursor_.remaining()) + " left in the buffer");
    }
  }

 private:
  void Truncated(std::string_view field) {
    check_->Fail(RejectCause::kTruncated, field, "the buffer ends inside this field");
  }
  Cursor cursor_;
  Checker* check_;
};

// The walks mirror the field order of the .lcm files up to (and including) each top-level
// array length; nested types have fixed-size arrays only. Strings after the last length are left
// to LCM's decode (a bad length there fails or throws, both caught).
void WalkLayout(LayoutWalk* walk, const camera_pose_t*) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  walk->Fixed("t_ns", 8);
  walk->String("camera");
}
void WalkLayout(LayoutWalk* walk, const rig_extrinsics_t*) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  walk->Fixed("t_ns", 8);
  walk->String("master");
  walk->Fixed("distance_unit", 1);
  walk->Count("num_slaves", slave_extrinsics_t()._getEncodedSizeNoHash());
}
void WalkLayout(LayoutWalk* walk, const rig_status_t*) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  walk->Count("num_cameras", camera_status_t()._getEncodedSizeNoHash());
}
void WalkLayout(LayoutWalk* walk, const image_t*) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  walk->Fixed("t_ns", 8);
  walk->String("camera");
  walk->Fixed("trigger_seq", 8);
  walk->Fixed("width", 4);
  walk->Fixed("height", 4);
  walk->Fixed("stride", 4);
  walk->String("pixel_format");
  walk->Fixed("encoding", 1);
  walk->Count("size", 1);
}

template <typename Message>
const char* TypeName();
template <>
const char* TypeName<camera_pose_t>() {
  return "camera_pose_t";
}
template <>
const char* TypeName<rig_extrinsics_t>() {
  return "rig_extrinsics_t";
}
template <>
const char* TypeName<rig_status_t>() {
  return "rig_status_t";
}
template <>
const char* TypeName<image_t>() {
  return "image_t";
}

int64_t ReadBigEndian(const uint8_t* data, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | data[i];
  return static_cast<int64_t>(v);
}

}  // namespace

// ---- Names and counters ----

std::string PoseChannel(std::string_view camera) { return "RIGCAL_POSE_" + std::string(camera); }
std::string ImageChannel(std::string_view camera) { return "RIGCAL_IMAGE_" + std::string(camera); }

const char* ToString(RejectCause cause) {
  switch (cause) {
    case RejectCause::kWrongType:
      return "wrong_type";
    case RejectCause::kWrongVersion:
      return "wrong_version";
    case RejectCause::kTruncated:
      return "truncated";
    case RejectCause::kOversize:
      return "oversize";
    case RejectCause::kMalformed:
      return "malformed";
    case RejectCause::kBadSize:
      return "bad_size";
    case RejectCause::kNonFinite:
      return "non_finite";
    case RejectCause::kNonUnitQuaternion:
      return "non_unit_quaternion";
    case RejectCause::kUnknownCamera:
      return "unknown_camera";
    case RejectCause::kOutOfRange:
      return "out_of_range";
  }
  return "unknown";
}

int64_t DecodeStats::TotalRejected() const {
  int64_t total = 0;
  for (int64_t n : rejected) total += n;
  return total;
}

std::string DecodeStats::Summary() const {
  std::string out =
      "accepted " + std::to_string(accepted) + ", rejected " + std::to_string(TotalRejected());
  std::string causes;
  for (int i = 0; i < kNumRejectCauses; ++i) {
    if (rejected[i] == 0) continue;
    if (!causes.empty()) causes += ", ";
    causes +=
        std::string(ToString(static_cast<RejectCause>(i))) + " " + std::to_string(rejected[i]);
  }
  if (!causes.empty()) out += " (" + causes + ")";
  return out;
}

// ---- Checks ----

std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      camera_pose_t* msg) {
  Checker check(channel, "camera_pose_t");
  check.Version(msg->version, camera_pose_t::VERSION);
  check.Finite("q", msg->q, 4);
  check.Finite("C", msg->C, 3);
  check.Finite("quality", msg->quality);
  if (msg->has_covariance) check.Finite("covariance", msg->covariance, 36);
  check.Quaternion("q", msg->q);
  check.CameraName("camera", msg->camera, names, 0, "the rig's cameras");
  check.AtLeast<int64_t>("utime", msg->utime, 0);
  check.AtLeast<int64_t>("t_ns", msg->t_ns, 0);
  check.AtLeast<int64_t>("trigger_seq", msg->trigger_seq, -1);
  check.AtLeast<int32_t>("segment", msg->segment, 0);
  check.InRange("quality", msg->quality, 0.0, 1.0);
  if (msg->has_covariance) {
    const double* cov = msg->covariance;
    double max_abs = 0.0;
    for (int i = 0; i < 36; ++i) max_abs = std::max(max_abs, std::abs(cov[i]));
    for (int r = 0; r < 6 && check.ok(); ++r) {
      check.AtLeast("covariance[" + std::to_string(r * 7) + "]", cov[r * 7], 0.0);
      for (int c = r + 1; c < 6; ++c) {
        if (std::abs(cov[r * 6 + c] - cov[c * 6 + r]) > 1e-9 * std::max(1.0, max_abs)) {
          check.Fail(RejectCause::kOutOfRange, "covariance",
                     "not symmetric: element (" + std::to_string(r) + ", " + std::to_string(c) +
                         ") = " + FormatNumber(cov[r * 6 + c]) + ", (" + std::to_string(c) + ", " +
                         std::to_string(r) + ") = " + FormatNumber(cov[c * 6 + r]));
          break;
        }
      }
    }
  }
  return check.TakeRejection();
}

std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      rig_extrinsics_t* msg) {
  Checker check(channel, "rig_extrinsics_t");
  check.Version(msg->version, rig_extrinsics_t::VERSION);
  check.Count("num_slaves", msg->num_slaves, msg->slaves.size(), "slaves");
  if (!check.ok()) return check.TakeRejection();
  check.CameraName("master", msg->master, names, 0, "the rig's cameras");
  if (check.ok() && !names.empty() && msg->master != names[0]) {
    check.Fail(RejectCause::kUnknownCamera, "master",
               "camera '" + msg->master + "' is not the rig's master '" + names[0] + "'");
  }
  check.AtLeast<int64_t>("utime", msg->utime, 0);
  check.AtLeast<int64_t>("t_ns", msg->t_ns, 0);
  check.InRange<int8_t>("distance_unit", msg->distance_unit, rig_extrinsics_t::UNIT_MASTER_ODOMETRY,
                        rig_extrinsics_t::UNIT_METRE);
  std::set<std::string> seen = {msg->master};
  for (size_t i = 0; i < msg->slaves.size() && check.ok(); ++i) {
    const std::string field = "slaves[" + std::to_string(i) + "]";
    Checker nested = check.Nested(field);
    CheckSlave(names, &msg->slaves[i], &nested);
    check.Merge(std::move(nested));
    if (check.ok() && !seen.insert(msg->slaves[i].name).second) {
      check.Fail(RejectCause::kOutOfRange, field + ".name",
                 "camera '" + msg->slaves[i].name + "' appears twice");
    }
  }
  return check.TakeRejection();
}

std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      rig_status_t* msg) {
  Checker check(channel, "rig_status_t");
  check.Version(msg->version, rig_status_t::VERSION);
  check.Count("num_cameras", msg->num_cameras, msg->cameras.size(), "cameras");
  if (!check.ok()) return check.TakeRejection();
  check.Finite("cpu_percent", msg->cpu_percent);
  check.AtLeast<int64_t>("utime", msg->utime, 0);
  check.AtLeast<int64_t>("sync_sets_emitted", msg->sync_sets_emitted, 0);
  check.AtLeast<int32_t>("sync_capacity", msg->sync_capacity, 0);
  check.InRange<int32_t>("sync_fill", msg->sync_fill, 0, msg->sync_capacity);
  check.InRange<int8_t>("estimator_state", msg->estimator_state, rig_status_t::ESTIMATOR_IDLE,
                        rig_status_t::ESTIMATOR_FAILED);
  check.AtLeast("cpu_percent", msg->cpu_percent, 0.0);
  check.AtLeast<int64_t>("rss_bytes", msg->rss_bytes, 0);
  std::set<std::string> seen;
  for (size_t i = 0; i < msg->cameras.size() && check.ok(); ++i) {
    const std::string field = "cameras[" + std::to_string(i) + "]";
    Checker nested = check.Nested(field);
    CheckCameraStatus(names, &msg->cameras[i], &nested);
    check.Merge(std::move(nested));
    if (check.ok() && !seen.insert(msg->cameras[i].name).second) {
      check.Fail(RejectCause::kOutOfRange, field + ".name",
                 "camera '" + msg->cameras[i].name + "' appears twice");
    }
  }
  return check.TakeRejection();
}

std::optional<Rejection> CheckMessage(std::string_view channel, const CameraNames& names,
                                      image_t* msg) {
  Checker check(channel, "image_t");
  check.Version(msg->version, image_t::VERSION);
  check.Count("size", msg->size, msg->data.size(), "data");
  if (!check.ok()) return check.TakeRejection();
  check.CameraName("camera", msg->camera, names, 0, "the rig's cameras");
  check.AtLeast<int64_t>("utime", msg->utime, 0);
  check.AtLeast<int64_t>("t_ns", msg->t_ns, 0);
  check.AtLeast<int64_t>("trigger_seq", msg->trigger_seq, -1);
  check.AtLeast<int32_t>("width", msg->width, 0);
  check.AtLeast<int32_t>("height", msg->height, 0);
  check.AtLeast<int32_t>("stride", msg->stride, 0);
  check.InRange<int8_t>("encoding", msg->encoding, image_t::ENCODING_RAW, image_t::ENCODING_PNG);
  if (check.ok() && msg->pixel_format.size() != 4) {
    check.Fail(RejectCause::kOutOfRange, "pixel_format",
               "'" + msg->pixel_format + "' is not a 4-character fourcc");
  }
  if (!check.ok()) return check.TakeRejection();
  if (msg->encoding == image_t::ENCODING_RAW) {
    const int bytes_per_pixel = std::max(1, BytesPerPixel(msg->pixel_format));
    const int64_t min_stride = int64_t{msg->width} * bytes_per_pixel;
    const int64_t expected_size = int64_t{msg->stride} * msg->height;
    if (msg->stride < min_stride) {
      check.Fail(RejectCause::kBadSize, "stride",
                 std::to_string(msg->stride) + " bytes is less than width " +
                     std::to_string(msg->width) + " x " + std::to_string(bytes_per_pixel) +
                     " bytes of " + msg->pixel_format);
    } else if (msg->size != expected_size) {
      check.Fail(RejectCause::kBadSize, "size",
                 std::to_string(msg->size) +
                     " bytes but stride x height = " + std::to_string(expected_size));
    }
  } else if (msg->size == 0) {
    check.Fail(RejectCause::kBadSize, "size", "empty compressed image");
  }
  return check.TakeRejection();
}

// ---- Conversion ----

Expected<camera_pose_t> CameraPoseToLcm(const CameraPose& pose, const CameraNames& names,
                                        int64_t utime, const Matrix6d* covariance) {
  if (pose.camera < 0 || static_cast<size_t>(pose.camera) >= names.size()) {
    return Error{"CameraPoseToLcm: camera index " + std::to_string(pose.camera) +
                 " is not in the name table of " + std::to_string(names.size()) + " cameras"};
  }
  camera_pose_t msg;
  msg.version = camera_pose_t::VERSION;
  msg.utime = utime;
  msg.t_ns = pose.t_ns;
  msg.camera = names[pose.camera];
  msg.trigger_seq = pose.trigger_seq;
  msg.segment = pose.segment;
  const Eigen::Quaterniond& q = pose.pose.q;
  msg.q[0] = q.w();
  msg.q[1] = q.x();
  msg.q[2] = q.y();
  msg.q[3] = q.z();
  for (int i = 0; i < 3; ++i) msg.C[i] = pose.pose.C[i];
  msg.quality = pose.quality;
  msg.has_covariance = covariance != nullptr;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) msg.covariance[r * 6 + c] = covariance ? (*covariance)(r, c) : 0.0;
  }
  if (std::optional<Rejection> rejection = CheckMessage(PoseChannel(msg.camera), names, &msg)) {
    return Error{rejection->message};
  }
  return msg;
}

Expected<PoseMessage> CameraPoseFromLcm(std::string_view channel, const camera_pose_t& msg,
                                        const CameraNames& names) {
  camera_pose_t checked = msg;
  if (std::optional<Rejection> rejection = CheckMessage(channel, names, &checked)) {
    return Error{rejection->message};
  }
  const auto it = std::find(names.begin(), names.end(), checked.camera);
  if (it == names.end()) {  // only reachable with an empty table
    return Error{std::string(channel) + ": camera_pose_t.camera: camera '" + checked.camera +
                 "' is not one of the rig's cameras (" + ToString(RejectCause::kUnknownCamera) +
                 ")"};
  }
  PoseMessage out;
  out.utime = checked.utime;
  out.pose.camera = static_cast<int>(it - names.begin());
  out.pose.t_ns = checked.t_ns;
  out.pose.trigger_seq = checked.trigger_seq;
  out.pose.segment = checked.segment;
  out.pose.pose.q = Eigen::Quaterniond(checked.q[0], checked.q[1], checked.q[2], checked.q[3]);
  out.pose.pose.C = Eigen::Vector3d(checked.C[0], checked.C[1], checked.C[2]);
  out.pose.quality = checked.quality;
  if (checked.has_covariance) {
    Matrix6d cov;
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) cov(r, c) = checked.covariance[r * 6 + c];
    }
    out.covariance = cov;
  }
  return out;
}

int32_t SlaveFlags(const SlaveCalibration& slave) {
  int32_t flags = slave.usable() ? kFlagConverged : kFlagInitialising;
  if (slave.motion_model == MotionModel::kTranslational || !slave.position_observable) {
    flags |= kFlagTranslationalOnly;
  }
  if (slave.observability.planar) {
    flags |= kFlagPlanar;
    if (slave.unobservable_from_prior) flags |= kFlagAxisFromPrior;
  }
  return flags;
}

Expected<slave_extrinsics_t> SlaveCalibrationToLcm(const SlaveCalibration& slave) {
  const bool usable = slave.usable();
  const std::string who = "slave '" + slave.name + "'";
  const auto or_zero = [](double v) { return std::isfinite(v) ? v : 0.0; };

  slave_extrinsics_t msg;
  msg.name = slave.name;
  Eigen::Quaterniond q = slave.estimate.q;
  Eigen::Vector3d C = slave.estimate.C;
  double scale = slave.estimate.scale;
  int32_t segment = 0;
  double scale_std = 0.0;
  if (!slave.scales.empty()) {
    const SegmentScale& current = *std::max_element(
        slave.scales.begin(), slave.scales.end(),
        [](const SegmentScale& a, const SegmentScale& b) { return a.segment < b.segment; });
    scale = current.scale;
    segment = current.segment;
    scale_std = current.std;
  }
  if (!usable) {  // placeholders for what a failed estimate left undefined
    if (!q.coeffs().allFinite() || q.norm() == 0.0) q = Eigen::Quaterniond::Identity();
    if (!C.allFinite()) C.setZero();
    if (!std::isfinite(scale)) scale = 1.0;
  } else if (!q.coeffs().allFinite() || !C.allFinite() || !std::isfinite(scale)) {
    return Error{who + " is usable (" + ToString(slave.termination) +
                 ") but its estimate is not finite"};
  }
  if (q.norm() > 0.0) q.normalize();
  msg.q[0] = q.w();
  msg.q[1] = q.x();
  msg.q[2] = q.y();
  msg.q[3] = q.z();
  for (int i = 0; i < 3; ++i) msg.C[i] = C[i];
  msg.scale = scale;
  msg.segment = segment;
  msg.rot_std_deg = or_zero(slave.rot_std_deg);
  for (int i = 0; i < 3; ++i) msg.pos_std[i] = or_zero(slave.pos_std[i]);
  msg.scale_std = or_zero(scale_std);
  msg.motions_used = slave.motions.used;
  msg.motions_rejected = slave.motions.rejected();

  const Observability& obs = slave.observability;
  msg.rotation_eigen_gap = or_zero(obs.rotation_eigenvalues[1] - obs.rotation_eigenvalues[0]);
  msg.position_min_eigenvalue = or_zero(obs.position_min_eigenvalue);
  msg.axis_spread_deg = or_zero(obs.axis_spread_deg);
  msg.flags = SlaveFlags(slave);
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  const bool axis_known = obs.planar_axis.allFinite() && obs.planar_axis.norm() > 0.5;
  if (obs.planar && !axis_known) {
    return Error{who + ": observability is planar but planar_axis is not a direction"};
  }
  if (axis_known) axis = obs.planar_axis.normalized();
  for (int i = 0; i < 3; ++i) msg.planar_axis[i] = axis[i];
  msg.axis_offset_std = 0.0;
  if (axis_known && usable && slave.position_observable) {
    if (obs.planar && !slave.unobservable_from_prior) {
      msg.axis_offset_std = -1.0;  // unknown
    } else if (std::isfinite(slave.axis_offset_std) && slave.axis_offset_std >= 0.0) {
      msg.axis_offset_std = slave.axis_offset_std;
    } else if (!obs.planar) {
      msg.axis_offset_std =
          std::sqrt(std::max(0.0, axis.dot(slave.pos_std.cwiseAbs2().asDiagonal() * axis)));
    }
  }
  msg.message = ToString(slave.termination);
  if (!slave.message.empty()) msg.message += ": " + slave.message;

  Checker check(kExtrinsicsChannel, "slave_extrinsics_t");
  CheckSlave({}, &msg, &check);
  if (std::optional<Rejection> rejection = check.TakeRejection()) {
    return Error{who + ": " + rejection->message};
  }
  return msg;
}

Expected<rig_extrinsics_t> RigCalibrationToLcm(const RigCalibration& result, int64_t utime,
                                               int64_t t_ns, int8_t distance_unit) {
  rig_extrinsics_t msg;
  msg.version = rig_extrinsics_t::VERSION;
  msg.utime = utime;
  msg.t_ns = t_ns;
  msg.master = result.master;
  msg.distance_unit = distance_unit;
  for (const SlaveCalibration& slave : result.slaves) {
    Expected<slave_extrinsics_t> converted = SlaveCalibrationToLcm(slave);
    if (!converted) return Error{converted.error()};
    msg.slaves.push_back(std::move(converted).value());
  }
  msg.num_slaves = static_cast<int32_t>(msg.slaves.size());
  if (std::optional<Rejection> rejection = CheckMessage(kExtrinsicsChannel, {}, &msg)) {
    return Error{rejection->message};
  }
  return msg;
}

// ---- MessageValidator ----

MessageValidator::MessageValidator(CameraNames camera_names) : names_(std::move(camera_names)) {}

Error MessageValidator::Reject(Rejection rejection) {
  ++stats_.rejected[static_cast<int>(rejection.cause)];
  Error error{rejection.message};
  stats_.last_rejection = std::move(rejection);
  return error;
}

template <typename Message>
std::optional<Rejection> MessageValidator::DecodeUncounted(std::string_view channel,
                                                           const void* data, int64_t size,
                                                           Message* msg) const {
  const char* type = TypeName<Message>();
  Checker check(channel, type);
  const auto* bytes = static_cast<const uint8_t*>(data);
  if (size < 0 || (size > 0 && data == nullptr)) {
    check.Fail(RejectCause::kTruncated, "buffer", "no data (size " + std::to_string(size) + ")");
    return check.TakeRejection();
  }
  if (size > INT_MAX) {
    check.Fail(RejectCause::kOversize, "buffer",
               std::to_string(size) + " bytes is more than LCM can decode");
    return check.TakeRejection();
  }
  if (size < kHashBytes) {
    check.Fail(RejectCause::kTruncated, "fingerprint",
               "the buffer has " + std::to_string(size) + " bytes, fewer than the fingerprint");
    return check.TakeRejection();
  }
  const int64_t hash = ReadBigEndian(bytes, kHashBytes);
  if (hash != Message::getHash()) {
    check.Fail(RejectCause::kWrongType, "fingerprint",
               "the buffer does not hold a " + std::string(type) + " of this schema");
    return check.TakeRejection();
  }
  if (size < kHashBytes + 2) {
    check.Fail(RejectCause::kTruncated, "version", "the buffer ends inside this field");
    return check.TakeRejection();
  }
  check.Version(static_cast<int16_t>(ReadBigEndian(bytes + kHashBytes, 2)), Message::VERSION);
  LayoutWalk walk(bytes, size, &check);
  WalkLayout(&walk, msg);
  if (!check.ok()) return check.TakeRejection();

  int decoded = -1;
  try {
    decoded = msg->decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {
    check.Fail(RejectCause::kMalformed, "buffer", std::string("LCM decode failed: ") + e.what());
    return check.TakeRejection();
  }
  if (decoded < 0) {
    check.Fail(RejectCause::kTruncated, "buffer",
               "LCM decode ran past the end of the " + std::to_string(size) + "-byte buffer");
  } else if (decoded != size) {
    check.Fail(RejectCause::kOversize, "buffer",
               std::to_string(size - decoded) + " bytes left over after the " +
                   std::to_string(decoded) + "-byte message");
  }
  if (!check.ok()) return check.TakeRejection();
  return CheckMessage(channel, names_, msg);
}

template <typename Message>
Expected<Message> MessageValidator::Decode(std::string_view channel, const void* data,
                                           int64_t size) {
  Message msg;
  if (std::optional<Rejection> rejection = DecodeUncounted(channel, data, size, &msg)) {
    return Reject(std::move(*rejection));
  }
  ++stats_.accepted;
  return msg;
}

Expected<PoseMessage> MessageValidator::DecodeCameraPose(std::string_view channel, const void* data,
                                                         int64_t size) {
  camera_pose_t msg;
  if (std::optional<Rejection> rejection = DecodeUncounted(channel, data, size, &msg)) {
    return Reject(std::move(*rejection));
  }
  const auto it = std::find(names_.begin(), names_.end(), msg.camera);
  if (it == names_.end()) {  // an empty table accepted the name; the index is needed here
    Checker check(channel, "camera_pose_t");
    check.Fail(RejectCause::kUnknownCamera, "camera",
               "camera '" + msg.camera + "' is not one of the rig's cameras");
    return Reject(*check.TakeRejection());
  }
  Expected<PoseMessage> pose = CameraPoseFromLcm(channel, msg, names_);
  if (!pose) return Reject(Rejection{RejectCause::kMalformed, pose.error()});  // not reached
  ++stats_.accepted;
  return pose;
}

template Expected<camera_pose_t> MessageValidator::Decode(std::string_view, const void*, int64_t);
template Expected<rig_extrinsics_t> MessageValidator::Decode(std::string_view, const void*,
                                                             int64_t);
template Expected<rig_status_t> MessageValidator::Decode(std::string_view, const void*, int64_t);
template Expected<image_t> MessageValidator::Decode(std::string_view, const void*, int64_t);

}  // namespace rigcal::tools
