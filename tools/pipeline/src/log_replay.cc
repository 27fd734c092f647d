// SPDX-License-Identifier: Apache-2.0
// CalibNode's replay of an LCM log (calib_node.h): the reader loop, the time window, pacing,
// the log-time timers and the image path through the pipeline.
#include <algorithm>
#include <cmath>
#include <optional>
#include <thread>

#include "calib_node_impl.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/pipeline/image_codec.h"

namespace rigcal::pipeline {
namespace {

constexpr char kImagePrefix[] = "RIGCAL_IMAGE_";

// Whether the log holds images of one of `names` (headers only: a quick scan).
Expected<bool> LogHasImages(const std::string& path, const lcm::CameraNames& names,
                            const lcm::LogReaderOptions& options) {
  auto scan = lcm::LogReader::Open(path, options);
  if (!scan) return scan.status();
  lcm::LogEvent event;
  while ((*scan)->NextHeader(&event) == lcm::LogReader::Outcome::kEvent) {
    if (event.channel.rfind(kImagePrefix, 0) != 0) continue;
    for (const std::string& name : names) {
      if (event.channel == lcm::ImageChannel(name)) return true;
    }
  }
  return false;
}

// The camera models VO needs for an image replay: cameras[].model of the config, or the
// simulated source's.
Expected<std::vector<std::shared_ptr<const camera::CameraModel>>> CameraModels(
    const io::RigConfig& config) {
  std::vector<std::shared_ptr<const camera::CameraModel>> models;
  for (size_t i = 0; i < config.cameras.size(); ++i) {
    const io::CameraConfig& camera = config.cameras[i];
    if (camera.spec) {
      auto model = camera::MakeCameraModel(*camera.spec);
      if (!model) return Error{config.path + ": camera '" + camera.name + "': " + model.error()};
      models.emplace_back(std::move(*model));
    } else if (config.simulated_source && i < config.simulated_source->cameras.size()) {
      models.push_back(config.simulated_source->cameras[i]);
    } else {
      return Error{config.path + ": camera '" + camera.name +
                   "' has no camera model; the VO of an image replay needs one (or replay the "
                   "log's poses with --poses-only)"};
    }
  }
  return models;
}

}  // namespace

Status ReplayOptions::Check() const {
  if (!(speed >= 0.0)) return Error{"speed: must be >= 0 (0 = as fast as possible)"};
  if (!(from_s >= 0.0)) return Error{"from_s: must be >= 0"};
  if (to_s >= 0.0 && to_s < from_s) return Error{"to_s: must be >= from_s (or < 0 = the end)"};
  if (max_event_bytes < 1) return Error{"max_event_bytes: must be >= 1"};
  if (frame_feed_capacity < 1) return Error{"frame_feed_capacity: must be >= 1"};
  if (!(frame_order_max_mb >= 1.0 && frame_order_max_mb <= 1e6)) {
    return Error{"frame_order_max_mb: must be in [1, 1e6]"};
  }
  return Status::Ok();
}

Status CalibNode::Impl::OpenLog() {
  if (const Status status = options.replay.Check(); !status.ok()) {
    return Error{"replay options: " + status.message()};
  }
  lcm::LogReaderOptions reader_options;
  reader_options.max_event_bytes = options.replay.max_event_bytes;
  auto opened = lcm::LogReader::Open(options.log_path, reader_options);
  if (!opened) return opened.status();
  reader = std::move(*opened);
  if (!options.publish_url.empty()) {
    if (Status status = CheckOutputUrl(options.publish_url); !status.ok()) return status;
    output = std::make_unique<::lcm::LCM>(options.publish_url);
    if (!output->good()) return Error{options.publish_url + ": cannot open the LCM URL"};
    MutexLock lock(output_mutex);
    published_file = PublishedFileCheck::ForUrl(options.publish_url);
  }
  if (options.replay.poses_only) return Status::Ok();
  auto images = LogHasImages(options.log_path, names, reader_options);
  if (!images) return images.status();
  if (!*images) return Status::Ok();

  auto models = CameraModels(config);
  if (!models) return models.status();
  const double rate_hz = 1e9 / static_cast<double>(config.online.sync.frame_period_ns);
  std::vector<std::unique_ptr<capture::CameraDevice>> devices;
  for (const std::string& name : names) {
    auto feed = std::make_unique<FrameFeedDevice>(
        name, rate_hz, static_cast<size_t>(options.replay.frame_feed_capacity));
    feeds.push_back(feed.get());
    devices.push_back(std::move(feed));
  }
  PipelineOptions pipeline_options;
  pipeline_options.lossless = true;
  pipeline_options.pose_sink = [this](const CameraPose& pose) { AcceptVoPose(pose); };
  pipeline = std::make_unique<Pipeline>(names, std::move(devices), std::move(*models),
                                        config.online, pipeline_options);
  images_invalid = std::make_unique<std::atomic<int64_t>[]>(names.size());
  frame_order = std::make_unique<ReplayFrameOrder>(
      static_cast<int>(names.size()),
      static_cast<int64_t>(std::llround(options.replay.frame_order_max_mb * 1e6)));
  summary.image_replay = true;
  log->info("{}: replaying the images through VO (--poses-only replays the poses)",
            options.log_path);
  return Status::Ok();
}

void CalibNode::Impl::AdvanceLogTime(int64_t t_ns) {
  if (t_ns <= clock_ns) return;
  clock_ns = t_ns;
  if (first_stamp_ns < 0) first_stamp_ns = t_ns;
  bool caught_up = false;
  int job = 0;
  int64_t deadline = 0;
  while (schedule.NextDue(clock_ns, &job, &deadline)) {
    if (!caught_up) {
      calibrator->Drain();
      caught_up = true;
    }
    RunJob(job, deadline / 1000);
  }
}

ReplayProgress CalibNode::Impl::Progress() const {
  ReplayProgress p;
  p.bytes_read = reader ? reader->position() : 0;
  p.log_bytes = reader ? reader->size() : 0;
  p.log_time_s = summary.log_span_s;
  p.sets = calibrator->sync_stats().sets_popped;
  return p;
}

// One event of the log decoded for the replay: an image of a rig camera (image replay) or a
// pose. Skipped and rejected events are counted here; false = nothing to hand on.
bool CalibNode::Impl::DecodeReplayEvent(const lcm::LogEvent& event, ReplayItem* item) {
  const bool images = pipeline != nullptr;
  const bool ours = event.channel.rfind(images ? kImagePrefix : "RIGCAL_POSE_", 0) == 0;
  if (!ours) {
    ++summary.skipped_channels[event.channel];
    return false;
  }
  const auto size = static_cast<int64_t>(event.data.size());
  item->camera = CameraOfChannel(event.channel, images);
  if (images) {
    if (item->camera < 0) {
      ++summary.skipped_channels[event.channel];
      return false;
    }
    auto image = validator.Decode<image_t>(event.channel, event.data.data(), size);
    auto decoded =
        image ? FrameFromImage(*image, item->camera) : Expected<capture::Frame>(image.status());
    if (!decoded) {
      ++summary.cameras[item->camera].invalid;
      images_invalid[item->camera].fetch_add(1);
      Reject(decoded.error());
      return false;
    }
    item->frame = std::move(*decoded);
    item->t_ns = item->frame->t_ns;
    return true;
  }
  if (item->camera < 0) {
    HandlePose(event.channel, event.data.data(), size);
    return false;
  }
  auto decoded = validator.DecodeCameraPose(event.channel, event.data.data(), size);
  if (!decoded || decoded->pose.camera != item->camera) {
    ++summary.cameras[item->camera].invalid;
    Reject(decoded ? event.channel + ": camera_pose_t.camera does not match the channel"
                   : decoded.error());
    return false;
  }
  item->pose = decoded->pose;
  item->t_ns = item->pose->t_ns;
  return true;
}

int64_t CalibNode::Impl::PacerObserve(const ReplayItem& item) {
  const ReplayPacer::Step step = pacer.Observe(item.camera, item.t_ns, Clock::now());
  if (step == ReplayPacer::Step::kGlitch && !pacer_in_glitch) {
    pacer_in_glitch = true;
    log->warn(
        "{}: {} event stamped {} ns is {:.3f} s from the log time ({} ns; more than {:.3f} s): "
        "not paced and moves no clock, unless the events that follow confirm a new timeline "
        "(warned once per burst)",
        options.log_path, names[static_cast<size_t>(item.camera)], item.t_ns,
        static_cast<double>(pacer.last_gap_ns()) * 1e-9, pacer.now_ns(),
        static_cast<double>(pacer.CapNs()) * 1e-9);
  } else if (step == ReplayPacer::Step::kNewTime) {
    pacer_in_glitch = false;
    log->warn(
        "{}: the log time jumps by {:.3f} s to {} ns (confirmed by the events after it): "
        "the gap is not waited for, pacing goes on from the new time",
        options.log_path, static_cast<double>(pacer.last_gap_ns()) * 1e-9, item.t_ns);
  } else if (step == ReplayPacer::Step::kOnTime) {
    pacer_in_glitch = false;
  }
  // An event behind the log time (late in the file) keeps its own stamp for --from / --to.
  return step == ReplayPacer::Step::kGlitch ? pacer.now_ns() : item.t_ns;
}

void CalibNode::Impl::PaceReplay(const std::atomic<bool>& stop) {
  const double speed = options.replay.speed;
  if (speed <= 0.0) return;
  const Clock::time_point due = pacer.Due(speed);
  while (!stop.load() && Clock::now() < due) {
    std::this_thread::sleep_for(
        std::min<Clock::duration>(due - Clock::now(), std::chrono::milliseconds(100)));
  }
}

// The next event of the log, false at its end or damage (recorded in the summary).
bool CalibNode::Impl::ReadReplayEvent(lcm::LogEvent* event) {
  const lcm::LogReader::Outcome outcome = reader->Next(event);
  if (outcome == lcm::LogReader::Outcome::kEnd) {
    summary.end_of_log = true;
    return false;
  }
  if (outcome == lcm::LogReader::Outcome::kDamaged) {
    summary.end_of_log = true;
    summary.log_problem = reader->problem() + "; replayed the " +
                          std::to_string(summary.log_events) + " events before it";
    log->warn("{}", summary.log_problem);
    return false;
  }
  ++summary.log_events;
  return true;
}

// A frame read from the log, through the frame order to the cameras' feeds; false once stopped.
bool CalibNode::Impl::OrderAndFeed(capture::Frame frame, const std::atomic<bool>& stop) {
  const int camera = frame.camera;
  if (!frame_order->Add(std::move(frame))) {
    if (++summary.cameras[camera].late_frames == 1) {
      log->warn(
          "{}: a frame of {} comes after frames of the other cameras stamped later were "
          "fed ({:.0f} MB of frames held could not wait for it): late frames are dropped "
          "and counted",
          options.log_path, names[static_cast<size_t>(camera)], options.replay.frame_order_max_mb);
    }
    return true;
  }
  std::vector<capture::Frame> ready;
  frame_order->TakeReady(&ready);
  return FeedInOrder(std::move(ready), stop);
}

// Hands frames (and progress marks) to their feeds, waiting for room but never past a stop.
bool CalibNode::Impl::FeedInOrder(std::vector<capture::Frame> frames,
                                  const std::atomic<bool>& stop) {
  for (capture::Frame& frame : frames) {
    const int camera = frame.camera;
    if (!frame.progress_mark) ++summary.cameras[camera].images;
    while (true) {
      if (stop.load()) return false;
      const auto outcome = feeds[camera]->FeedUntil(
          frame, std::chrono::steady_clock::now() + std::chrono::milliseconds(100));
      if (outcome == FrameFeedDevice::Fed::kStopped) return false;
      if (outcome == FrameFeedDevice::Fed::kFed) break;
    }
  }
  return true;
}

// The frames held at the end of the log, in stamp order; each camera's feed ends after its last
// one, so that the merge does not wait for a camera that has nothing more.
void CalibNode::Impl::FeedRest(std::vector<capture::Frame> rest, const std::atomic<bool>& stop) {
  std::vector<size_t> last(feeds.size(), 0);  // per camera: 1 + index of its last frame in rest
  for (size_t k = 0; k < rest.size(); ++k) last[static_cast<size_t>(rest[k].camera)] = k + 1;
  for (size_t c = 0; c < feeds.size(); ++c) {
    if (last[c] == 0) feeds[c]->End();
  }
  for (size_t k = 0; k < rest.size(); ++k) {
    const auto c = static_cast<size_t>(rest[k].camera);
    if (!FeedInOrder({std::move(rest[k])}, stop)) return;
    if (last[c] == k + 1) feeds[c]->End();
  }
}

void CalibNode::Impl::ReplayLog(const std::atomic<bool>& stop) {
  const ReplayOptions& replay = options.replay;
  if (pipeline) pipeline->Start();
  lcm::LogEvent event;
  int64_t window_start = -1;  // first stamp of the log: the origin of --from / --to
  const auto from_ns = static_cast<int64_t>(std::llround(replay.from_s * 1e9));
  const int64_t to_ns =
      replay.to_s < 0.0 ? -1 : static_cast<int64_t>(std::llround(replay.to_s * 1e9));
  Clock::time_point next_progress = Clock::now();
  const auto progress_period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options.progress_every_s));
  while (!stop.load() && ReadReplayEvent(&event)) {
    if (options.on_progress && Clock::now() >= next_progress) {
      options.on_progress(Progress());
      next_progress = Clock::now() + progress_period;
    }
    ReplayItem item;
    if (!DecodeReplayEvent(event, &item)) continue;
    // The message's stamp decides the window and the pacing (a glitched one: the log time).
    const int64_t t_ns = PacerObserve(item);
    if (window_start < 0) window_start = t_ns;
    const int64_t since_ns = t_ns - window_start;
    if (since_ns < from_ns) continue;
    if (to_ns >= 0 && since_ns > to_ns) break;
    summary.log_span_s =
        std::max(summary.log_span_s, static_cast<double>(since_ns - from_ns) * 1e-9);
    PaceReplay(stop);
    if (item.frame) {
      if (!OrderAndFeed(std::move(*item.frame), stop)) break;
    } else {
      AcceptOnLogTime(item.camera, *item.pose);
    }
  }
  if (pipeline) {
    // Every fed frame through the VO and its poses handed over, then the threads joined.
    std::vector<capture::Frame> rest;
    if (!stop.load()) frame_order->TakeAll(&rest);
    FeedRest(std::move(rest), stop);
    for (size_t c = 0; c < names.size(); ++c) {
      if (summary.cameras[c].late_frames == 0) continue;
      log->warn("{}: {} late frames of {} dropped", options.log_path,
                summary.cameras[c].late_frames, names[c]);
    }
    for (FrameFeedDevice* feed : feeds) feed->End();
    while (!pipeline->Finished() && !stop.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    pipeline->Stop();
  }
}

}  // namespace rigcal::pipeline
