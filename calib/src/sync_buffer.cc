#include "rigcal/calib/sync_buffer.h"

#include <cmath>
#include <condition_variable>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "sync_mutex.h"

namespace rigcal {
namespace {

constexpr int kMaxCameras = 256;
constexpr int kMaxCapacity = 1 << 20;
constexpr int64_t kMaxDurationNs = 3'600'000'000'000;  // 1 h: keeps stamp sums far from overflow

// A FIFO over storage allocated once: PushBack on a full ring overwrites the oldest slot.
template <typename T>
class FixedRing {
 public:
  FixedRing(size_t capacity, const T& prototype) : slots_(capacity, prototype) {}

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == slots_.size(); }
  T& operator[](size_t i) { return slots_[(head_ + i) % slots_.size()]; }
  const T& operator[](size_t i) const { return slots_[(head_ + i) % slots_.size()]; }
  T& front() { return slots_[head_]; }
  const T& front() const { return slots_[head_]; }

  // The slot after the newest one, now part of the ring (the caller fills it). The ring must
  // not be full.
  T& PushBack() {
    T& slot = slots_[(head_ + size_) % slots_.size()];
    ++size_;
    return slot;
  }
  void PopFront() {
    head_ = (head_ + 1) % slots_.size();
    --size_;
  }

 private:
  std::vector<T> slots_;
  size_t head_ = 0;
  size_t size_ = 0;
};

bool IsValid(const CameraPose& p) {
  return p.t_ns >= 0 && p.pose.q.coeffs().allFinite() && p.pose.q.coeffs().squaredNorm() > 0.0 &&
         p.pose.C.allFinite() && std::isfinite(p.quality);
}

// What identifies an entry in time: its stamp and trigger sequence number.
struct Key {
  int64_t t_ns = 0;
  int64_t seq = -1;
};

Key KeyOf(const CameraPose& p) { return {p.t_ns, p.trigger_seq}; }

}  // namespace

int64_t SyncOptions::EffectiveToleranceNs() const {
  return tolerance_ns > 0 ? tolerance_ns : frame_period_ns / 2;
}

int64_t SyncOptions::EffectiveMaxWaitNs() const {
  return max_wait_ns > 0 ? max_wait_ns : 3 * frame_period_ns;
}

bool SyncOptions::IsRequired(int camera) const {
  if (camera == 0 || required.empty()) return true;
  return camera > 0 && camera < static_cast<int>(required.size()) && required[camera];
}

Status SyncOptions::Check() const {
  std::ostringstream e;
  if (num_cameras < 1 || num_cameras > kMaxCameras)
    e << "num_cameras: must be in [1, " << kMaxCameras << "], got " << num_cameras;
  else if (capacity < 1 || capacity > kMaxCapacity)
    e << "capacity: must be in [1, " << kMaxCapacity << "], got " << capacity;
  else if (frame_period_ns <= 0 || frame_period_ns > kMaxDurationNs)
    e << "frame_period_ns: must be in (0, " << kMaxDurationNs << "], got " << frame_period_ns;
  else if (tolerance_ns < 0 || tolerance_ns > kMaxDurationNs)
    e << "tolerance_ns: must be in [0, " << kMaxDurationNs << "] (0 = frame_period_ns / 2), got "
      << tolerance_ns;
  else if (max_wait_ns < 0 || max_wait_ns > kMaxDurationNs)
    e << "max_wait_ns: must be in [0, " << kMaxDurationNs << "] (0 = 3 * frame_period_ns), got "
      << max_wait_ns;
  else if (!required.empty() && static_cast<int>(required.size()) != num_cameras)
    e << "required: must be empty or have num_cameras (" << num_cameras << ") flags, got "
      << required.size();
  else if (!required.empty() && !required[0])
    e << "required[0]: must be true: the master is in every set";
  else if (ready_capacity < 1 || ready_capacity > kMaxCapacity)
    e << "ready_capacity: must be in [1, " << kMaxCapacity << "], got " << ready_capacity;
  if (e.str().empty()) return Status::Ok();
  return Error{e.str()};
}

const char* ToString(PushResult result) {
  switch (result) {
    case PushResult::kAccepted:
      return "accepted";
    case PushResult::kStopped:
      return "stopped";
    case PushResult::kUnknownCamera:
      return "unknown_camera";
    case PushResult::kInvalid:
      return "invalid";
    case PushResult::kLate:
      return "late";
    case PushResult::kDuplicate:
      return "duplicate";
    case PushResult::kOutOfOrder:
      return "out_of_order";
  }
  return "?";
}

std::string SyncStats::BriefReport() const {
  std::ostringstream s;
  s << "sets " << sets_emitted << " (popped " << sets_popped << ", ready " << ready_fill;
  if (consumer_overflow) s << ", consumer_overflow " << consumer_overflow;
  s << ")";
  if (unknown_camera) s << " unknown_camera " << unknown_camera;
  for (size_t c = 0; c < cameras.size(); ++c) {
    const SyncCameraStats& k = cameras[c];
    s << " | cam" << c << " pushed " << k.pushed << " used " << k.used << " fill " << k.fill;
    auto field = [&](const char* name, uint64_t v) {
      if (v) s << ' ' << name << ' ' << v;
    };
    field("never_matched", k.never_matched);
    field("overflow", k.overflow);
    field("late", k.late);
    field("duplicate", k.duplicate);
    field("out_of_order", k.out_of_order);
    field("invalid", k.invalid);
    field("stopped", k.stopped);
    field("optional_missing", k.optional_missing);
  }
  return s.str();
}

// All state lives here, behind one mutex: a push does O(num_cameras * capacity) work, so finer
// locking would not pay.
class SyncBuffer::Impl {
 public:
  explicit Impl(const SyncOptions& options)
      : options_(options),
        n_(options.num_cameras),
        tolerance_ns_(options.EffectiveToleranceNs()),
        max_wait_ns_(options.EffectiveMaxWaitNs()),
        by_seq_(options.match_by_trigger_seq),
        ready_(static_cast<size_t>(options.ready_capacity),
               MatchedSet{0, std::vector<std::optional<CameraPose>>(options.num_cameras)}),
        candidates_(options.num_cameras) {
    for (int c = 0; c < n_; ++c) required_.push_back(options.IsRequired(c));
    cameras_.reserve(n_);
    for (int c = 0; c < n_; ++c) cameras_.emplace_back(static_cast<size_t>(options.capacity));
  }

  const SyncOptions& options() const { return options_; }

  PushResult Push(const CameraPose& pose) RIGCAL_EXCLUDES(mutex_) {
    SyncLock lock(mutex_);
    if (pose.camera < 0 || pose.camera >= n_) {
      ++unknown_camera_;
      return PushResult::kUnknownCamera;
    }
    CameraState& cam = cameras_[pose.camera];
    ++cam.stats.pushed;
    const PushResult result = Classify(pose);
    switch (result) {
      case PushResult::kAccepted:
        break;
      case PushResult::kStopped:
        ++cam.stats.stopped;
        return result;
      case PushResult::kInvalid:
        ++cam.stats.invalid;
        return result;
      case PushResult::kLate:
        ++cam.stats.late;
        return result;
      case PushResult::kDuplicate:
        ++cam.stats.duplicate;
        return result;
      case PushResult::kOutOfOrder:
        ++cam.stats.out_of_order;
        return result;
      case PushResult::kUnknownCamera:
        return result;
    }
    Accept(pose);
    if (Process(/*flush=*/false) > 0) ready_cv_.notify_all();
    return PushResult::kAccepted;
  }

  bool Pop(MatchedSet* out, std::chrono::milliseconds timeout) RIGCAL_EXCLUDES(mutex_) {
    if (out == nullptr) return false;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    SyncLock lock(mutex_);
    while (ready_.empty() && !stopped_) {
      if (ready_cv_.wait_until(lock.native(), deadline) == std::cv_status::timeout) break;
    }
    return TakeReady(out);
  }

  bool TryPop(MatchedSet* out) RIGCAL_EXCLUDES(mutex_) {
    if (out == nullptr) return false;
    SyncLock lock(mutex_);
    return TakeReady(out);
  }

  void Flush() RIGCAL_EXCLUDES(mutex_) {
    SyncLock lock(mutex_);
    if (Process(/*flush=*/true) > 0) ready_cv_.notify_all();
  }

  void Stop() RIGCAL_EXCLUDES(mutex_) {
    SyncLock lock(mutex_);
    stopped_ = true;
    ready_cv_.notify_all();
  }

  bool stopped() const RIGCAL_EXCLUDES(mutex_) {
    SyncLock lock(mutex_);
    return stopped_;
  }

  SyncStats stats() const RIGCAL_EXCLUDES(mutex_) {
    SyncStats s;
    s.cameras.resize(n_);
    SyncLock lock(mutex_);
    for (int c = 0; c < n_; ++c) {
      SyncCameraStats k = cameras_[c].stats;
      k.fill = cameras_[c].ring.size();
      s.cameras[c] = k;
      SyncCameraStats& t = s.total;
      t.pushed += k.pushed;
      t.used += k.used;
      t.stopped += k.stopped;
      t.invalid += k.invalid;
      t.late += k.late;
      t.duplicate += k.duplicate;
      t.out_of_order += k.out_of_order;
      t.overflow += k.overflow;
      t.never_matched += k.never_matched;
      t.optional_missing += k.optional_missing;
      t.fill += k.fill;
    }
    s.unknown_camera = unknown_camera_;
    s.sets_emitted = sets_emitted_;
    s.sets_popped = sets_popped_;
    s.consumer_overflow = consumer_overflow_;
    s.ready_fill = ready_.size();
    return s;
  }

 private:
  struct CameraState {
    explicit CameraState(size_t capacity) : ring(capacity, CameraPose{}) {}

    FixedRing<CameraPose> ring;   // strictly increasing t_ns
    bool any = false;             // an entry was ever accepted
    int64_t newest_t = 0;         // stamp of the newest accepted entry
    int64_t newest_seq = -1;      // highest trigger_seq accepted (-1: none)
    bool newest_has_seq = false;  // whether the newest accepted entry carries a trigger_seq
    bool any_used = false;        // an entry was a member of an emitted set
    Key last_used;                // the member of the last emitted set that had this camera
    SyncCameraStats stats;        // fill is filled in by stats()
  };

  // The partner of the current master entry in one slave ring.
  struct Candidate {
    int index = -1;  // in the ring; -1: none
    int64_t distance = 0;
    bool final = false;
  };

  // Both entries carry a trigger sequence number and trigger mode is on.
  bool SeqPair(int64_t seq_a, int64_t seq_b) const { return by_seq_ && seq_a >= 0 && seq_b >= 0; }

  // True when slave entry `s` cannot match any master entry newer than `m` (masters arrive with
  // increasing stamps and sequence numbers).
  bool Unmatchable(const Key& s, const Key& m) const {
    if (SeqPair(s.seq, m.seq)) return s.seq <= m.seq;
    return s.t_ns <= m.t_ns - tolerance_ns_;
  }

  PushResult Classify(const CameraPose& pose) const RIGCAL_REQUIRES(mutex_) {
    if (stopped_) return PushResult::kStopped;
    if (!IsValid(pose)) return PushResult::kInvalid;
    const CameraState& cam = cameras_[pose.camera];
    const Key key = KeyOf(pose);
    if (cam.any_used && (key.t_ns <= cam.last_used.t_ns ||
                         (SeqPair(key.seq, cam.last_used.seq) && key.seq <= cam.last_used.seq)))
      return PushResult::kLate;
    if (pose.camera != 0 && has_resolved_master_ && Unmatchable(key, last_resolved_master_))
      return PushResult::kLate;
    if (cam.any && (key.t_ns == cam.newest_t || (key.seq >= 0 && key.seq == cam.newest_seq)))
      return PushResult::kDuplicate;
    for (size_t i = 0; i < cam.ring.size(); ++i) {
      const CameraPose& e = cam.ring[i];
      if (e.t_ns == key.t_ns || (key.seq >= 0 && e.trigger_seq == key.seq))
        return PushResult::kDuplicate;
    }
    if (cam.any && key.t_ns < cam.newest_t) return PushResult::kOutOfOrder;
    if (SeqPair(key.seq, cam.newest_seq) && key.seq < cam.newest_seq)
      return PushResult::kOutOfOrder;
    return PushResult::kAccepted;
  }

  void Accept(const CameraPose& pose) RIGCAL_REQUIRES(mutex_) {
    CameraState& cam = cameras_[pose.camera];
    if (cam.ring.full()) {
      cam.ring.PopFront();
      ++cam.stats.overflow;
    }
    cam.ring.PushBack() = pose;
    cam.any = true;
    cam.newest_t = pose.t_ns;
    cam.newest_has_seq = pose.trigger_seq >= 0;
    if (pose.trigger_seq >= 0) cam.newest_seq = pose.trigger_seq;
    if (!has_stream_) {
      has_stream_ = true;
      stream_start_ns_ = pose.t_ns;
      now_ns_ = pose.t_ns;
    }
    if (pose.t_ns > now_ns_) now_ns_ = pose.t_ns;
  }

  // Stream time against which master entries time out.
  int64_t WaitClockNs() const RIGCAL_REQUIRES(mutex_) {
    return by_seq_ ? cameras_[0].newest_t : now_ns_;
  }

  // The entry of slave `j` closest to master `m` among those that match it.
  Candidate FindCandidate(int j, const CameraPose& m) const RIGCAL_REQUIRES(mutex_) {
    Candidate best;
    const FixedRing<CameraPose>& ring = cameras_[j].ring;
    for (size_t i = 0; i < ring.size(); ++i) {
      const CameraPose& s = ring[i];
      if (SeqPair(s.trigger_seq, m.trigger_seq)) {
        if (s.trigger_seq == m.trigger_seq) return {static_cast<int>(i), 0, false};
        continue;
      }
      const int64_t d = s.t_ns >= m.t_ns ? s.t_ns - m.t_ns : m.t_ns - s.t_ns;
      if (d <= tolerance_ns_ && (best.index < 0 || d < best.distance))
        best = {static_cast<int>(i), d, false};
      if (!by_seq_ && s.t_ns > m.t_ns) break;  // later entries are farther away
    }
    return best;
  }

  // Whether an entry still to come from slave `j` could match master `m` strictly closer than
  // `c` (any match at all when c has none).
  bool CloserCanArrive(int j, const CameraPose& m, const Candidate& c) const
      RIGCAL_REQUIRES(mutex_) {
    const CameraState& cam = cameras_[j];
    if (c.index >= 0 && c.distance == 0) return false;
    if (!cam.any) return true;
    if (by_seq_ && m.trigger_seq >= 0 && cam.newest_has_seq) return cam.newest_seq < m.trigger_seq;
    // Future stamps are > newest_t; closer means at most m.t_ns + reach.
    const int64_t reach = c.index >= 0 ? c.distance - 1 : tolerance_ns_;
    return cam.newest_t - m.t_ns < reach;
  }

  // An optional slave that fell more than max_wait behind the stream holds no set back.
  bool Stale(int j) const RIGCAL_REQUIRES(mutex_) {
    if (by_seq_) return false;
    const CameraState& cam = cameras_[j];
    const int64_t newest = cam.any ? cam.newest_t : stream_start_ns_;
    return now_ns_ - newest > max_wait_ns_;
  }

  // Resolves master entries from the oldest on (see the rule in the header); returns the
  // number of sets emitted. `flush`: treat every master entry as timed out.
  int Process(bool flush) RIGCAL_REQUIRES(mutex_) {
    int emitted = 0;
    FixedRing<CameraPose>& masters = cameras_[0].ring;
    while (!masters.empty()) {
      const CameraPose& m = masters.front();
      bool impossible = false;
      bool all_final = true;
      bool required_present = true;
      for (int j = 1; j < n_ && !impossible; ++j) {
        Candidate& c = candidates_[j];
        c = FindCandidate(j, m);
        c.final = !CloserCanArrive(j, m, c) || (!required_[j] && Stale(j));
        all_final = all_final && c.final;
        if (required_[j] && c.index < 0) {
          required_present = false;
          impossible = c.final;
        }
      }
      if (impossible) {
        DropMaster();
        continue;
      }
      if (all_final) {
        Emit();
        ++emitted;
        continue;
      }
      if (!flush && WaitClockNs() - m.t_ns <= max_wait_ns_) break;
      if (required_present) {
        Emit();
        ++emitted;
      } else {
        DropMaster();
      }
    }
    return emitted;
  }

  // Emits the oldest master entry with candidates_ as partners.
  void Emit() RIGCAL_REQUIRES(mutex_) {
    if (ready_.full()) {
      ready_.PopFront();
      ++consumer_overflow_;
    }
    MatchedSet& set = ready_.PushBack();
    CameraState& master = cameras_[0];
    const Key m = KeyOf(master.ring.front());
    set.t_ns = m.t_ns;
    set.poses[0] = master.ring.front();
    master.ring.PopFront();
    ++master.stats.used;
    master.any_used = true;
    master.last_used = m;
    for (int j = 1; j < n_; ++j) {
      CameraState& cam = cameras_[j];
      const Candidate& c = candidates_[j];
      if (c.index < 0) {
        set.poses[j].reset();
        ++cam.stats.optional_missing;
        continue;
      }
      set.poses[j] = cam.ring[c.index];
      for (int i = 0; i < c.index; ++i) {
        cam.ring.PopFront();
        ++cam.stats.never_matched;
      }
      cam.last_used = KeyOf(cam.ring.front());
      cam.any_used = true;
      cam.ring.PopFront();
      ++cam.stats.used;
    }
    ++sets_emitted_;
    Resolved(m);
  }

  void DropMaster() RIGCAL_REQUIRES(mutex_) {
    CameraState& master = cameras_[0];
    const Key m = KeyOf(master.ring.front());
    master.ring.PopFront();
    ++master.stats.never_matched;
    Resolved(m);
  }

  // Master entry `m` left the buffer: slave entries that cannot match a later master go.
  void Resolved(const Key& m) RIGCAL_REQUIRES(mutex_) {
    has_resolved_master_ = true;
    last_resolved_master_ = m;
    for (int j = 1; j < n_; ++j) {
      CameraState& cam = cameras_[j];
      while (!cam.ring.empty() && Unmatchable(KeyOf(cam.ring.front()), m)) {
        cam.ring.PopFront();
        ++cam.stats.never_matched;
      }
    }
  }

  bool TakeReady(MatchedSet* out) RIGCAL_REQUIRES(mutex_) {
    if (ready_.empty()) return false;
    const MatchedSet& set = ready_.front();
    out->t_ns = set.t_ns;
    out->poses = set.poses;  // reuses out's storage once it has num_cameras slots
    ready_.PopFront();
    ++sets_popped_;
    return true;
  }

  // Immutable after construction.
  const SyncOptions options_;
  const int n_;
  const int64_t tolerance_ns_;
  const int64_t max_wait_ns_;
  const bool by_seq_;
  std::vector<bool> required_;  // per camera; [0] is true

  mutable SyncMutex mutex_;
  std::condition_variable ready_cv_;  // signalled when a set is emitted and on Stop
  std::vector<CameraState> cameras_ RIGCAL_GUARDED_BY(mutex_);
  FixedRing<MatchedSet> ready_ RIGCAL_GUARDED_BY(mutex_);
  std::vector<Candidate> candidates_ RIGCAL_GUARDED_BY(mutex_);  // scratch of Process, per camera
  bool has_stream_ RIGCAL_GUARDED_BY(mutex_) = false;
  int64_t stream_start_ns_ RIGCAL_GUARDED_BY(mutex_) = 0;  // first accepted stamp
  int64_t now_ns_ RIGCAL_GUARDED_BY(mutex_) = 0;           // newest accepted stamp, any camera
  bool has_resolved_master_ RIGCAL_GUARDED_BY(mutex_) = false;
  Key last_resolved_master_ RIGCAL_GUARDED_BY(mutex_);  // last master emitted or dropped
  bool stopped_ RIGCAL_GUARDED_BY(mutex_) = false;
  uint64_t unknown_camera_ RIGCAL_GUARDED_BY(mutex_) = 0;
  uint64_t sets_emitted_ RIGCAL_GUARDED_BY(mutex_) = 0;
  uint64_t sets_popped_ RIGCAL_GUARDED_BY(mutex_) = 0;
  uint64_t consumer_overflow_ RIGCAL_GUARDED_BY(mutex_) = 0;
};

namespace {

const SyncOptions& Checked(const SyncOptions& options) {
  RequireValid(options.Check(), "SyncOptions");
  return options;
}

}  // namespace

SyncBuffer::SyncBuffer(const SyncOptions& options)
    : impl_(std::make_unique<Impl>(Checked(options))) {}

SyncBuffer::~SyncBuffer() = default;

const SyncOptions& SyncBuffer::options() const { return impl_->options(); }
PushResult SyncBuffer::Push(const CameraPose& pose) { return impl_->Push(pose); }
bool SyncBuffer::Pop(MatchedSet* out, std::chrono::milliseconds timeout) {
  return impl_->Pop(out, timeout);
}
bool SyncBuffer::TryPop(MatchedSet* out) { return impl_->TryPop(out); }
void SyncBuffer::Flush() { impl_->Flush(); }
void SyncBuffer::Stop() { impl_->Stop(); }
bool SyncBuffer::stopped() const { return impl_->stopped(); }
SyncStats SyncBuffer::stats() const { return impl_->stats(); }

}  // namespace rigcal
