// SPDX-License-Identifier: Apache-2.0
#include "rigcal/monitor/status_monitor.h"

#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "rigcal/base/logging.h"
#include "rigcal/lcm/bus_exposure.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/status_message.h"

namespace rigcal::monitor {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t, Clock::time_point now) {
  return std::chrono::duration<double>(now - t).count();
}

void OnMessage(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel, StatusMonitor* monitor) {
  monitor->Handle(channel, rbuf->data, rbuf->data_size);
}

}  // namespace

struct StatusMonitor::Impl {
  std::string url;
  ::lcm::LCM* bus = nullptr;
  std::unique_ptr<::lcm::LCM> owned_bus;
  lcm::MessageValidator validator;  // any camera names: the monitor does not know the rig
  Clock::time_point started = Clock::now();
  std::optional<rig_status_t> status;
  std::optional<rig_extrinsics_t> extrinsics;
  Clock::time_point status_at;
  Clock::time_point extrinsics_at;
  int64_t status_received = 0;
  int64_t extrinsics_received = 0;
  int handled = 0;
  std::shared_ptr<spdlog::logger> log = ModuleLogger("tools");
};

StatusMonitor::StatusMonitor(std::string url, ::lcm::LCM* lcm) : impl_(std::make_unique<Impl>()) {
  impl_->url = std::move(url);
  impl_->bus = lcm;
}

StatusMonitor::~StatusMonitor() = default;

Status StatusMonitor::Open() {
  Impl& m = *impl_;
  if (m.bus == nullptr) {
    m.owned_bus = std::make_unique<::lcm::LCM>(m.url);
    if (!m.owned_bus->good()) {
      return Error{(m.url.empty() ? std::string("the default LCM URL") : m.url) +
                   ": cannot open LCM (udpm:// needs a multicast route, e.g. on lo: "
                   "ip route add 224.0.0.0/4 dev lo)"};
    }
    m.bus = m.owned_bus.get();
  }
  m.bus->subscribeFunction(lcm::kStatusChannel, &OnMessage, this);
  m.bus->subscribeFunction(lcm::kExtrinsicsChannel, &OnMessage, this);
  m.started = Clock::now();
  return {};
}

void StatusMonitor::Handle(const std::string& channel, const void* data, int64_t size) {
  Impl& m = *impl_;
  ++m.handled;
  if (channel == lcm::kStatusChannel) {
    Expected<rig_status_t> msg = m.validator.Decode<rig_status_t>(channel, data, size);
    if (!msg) {
      m.log->warn("{}", msg.error());
      return;
    }
    m.status = std::move(msg).value();
    m.status_at = Clock::now();
    ++m.status_received;
  } else if (channel == lcm::kExtrinsicsChannel) {
    Expected<rig_extrinsics_t> msg = m.validator.Decode<rig_extrinsics_t>(channel, data, size);
    if (!msg) {
      m.log->warn("{}", msg.error());
      return;
    }
    m.extrinsics = std::move(msg).value();
    m.extrinsics_at = Clock::now();
    ++m.extrinsics_received;
  }
}

int StatusMonitor::Poll(std::chrono::milliseconds timeout) {
  Impl& m = *impl_;
  m.handled = 0;
  const int rc = m.bus->handleTimeout(static_cast<int>(std::max<int64_t>(0, timeout.count())));
  if (rc < 0) return -1;
  return m.handled;
}

MonitorSnapshot StatusMonitor::Snapshot() const {
  const Impl& m = *impl_;
  const Clock::time_point now = Clock::now();
  MonitorSnapshot s;
  s.source = m.url;
  s.status = m.status;
  s.extrinsics = m.extrinsics;
  s.status_age_s = m.status ? SecondsSince(m.status_at, now) : -1.0;
  s.extrinsics_age_s = m.extrinsics ? SecondsSince(m.extrinsics_at, now) : -1.0;
  s.status_received = m.status_received;
  s.extrinsics_received = m.extrinsics_received;
  s.decode = m.validator.stats();
  s.listening_s = SecondsSince(m.started, now);
  return s;
}

namespace {

std::string View(const MonitorSnapshot& snapshot, const StatusRunOptions& options) {
  if (options.json) return SnapshotToJson(snapshot).dump() + "\n";
  return FormatDashboard(snapshot, options.width);
}

int RunOnce(StatusMonitor& monitor, const StatusRunOptions& options, std::ostream& out,
            const std::atomic<bool>& stop) {
  const Clock::time_point deadline =
      Clock::now() +
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.timeout_s));
  while (!stop.load() && Clock::now() < deadline) {
    const MonitorSnapshot s = monitor.Snapshot();
    if (s.status && s.extrinsics) break;
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (monitor.Poll(std::min(left, std::chrono::milliseconds(100))) < 0) break;
  }
  const MonitorSnapshot snapshot = monitor.Snapshot();
  out << (options.json ? SnapshotToJson(snapshot).dump(2) + "\n" : View(snapshot, options));
  out.flush();
  return static_cast<int>(HealthOf(snapshot));
}

}  // namespace

int RunStatusMonitor(const StatusRunOptions& options, std::ostream& out, std::ostream& err,
                     const std::atomic<bool>& stop, ::lcm::LCM* lcm) {
  StatusMonitor monitor(options.url, lcm);
  Status status = monitor.Open();
  if (status.ok() && lcm == nullptr && !options.lcm_network) {
    status = lcm::CheckBusStaysOnHost(options.url);
  }
  if (!status.ok()) {
    err << "rigcal status: " << status.message() << "\n";
    return static_cast<int>(Health::kNoData);
  }
  if (options.once) return RunOnce(monitor, options, out, stop);

  if (options.ansi) out << "\x1b[2J";  // clear once; every frame then redraws from home
  const auto refresh =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.refresh_s));
  Clock::time_point next_frame = Clock::now();
  int64_t statuses_shown = 0;
  while (!stop.load()) {
    const Clock::time_point now = Clock::now();
    if (options.ansi && now >= next_frame) {
      out << AnsiFrame(FormatDashboard(monitor.Snapshot(), options.width));
      out.flush();
      next_frame = now + refresh;
    }
    const MonitorSnapshot s = monitor.Snapshot();
    if (!options.ansi && s.status_received > statuses_shown) {
      statuses_shown = s.status_received;
      out << (options.json ? "" : "---\n") << View(s, options);
      out.flush();
    }
    if (monitor.Poll(std::chrono::milliseconds(100)) < 0) {
      // file:// at the end of its log and broken buses end here.
      break;
    }
  }
  const MonitorSnapshot last = monitor.Snapshot();
  if (options.ansi) {  // the screen keeps the last state
    out << AnsiFrame(FormatDashboard(last, options.width));
    out.flush();
  }
  return static_cast<int>(HealthOf(last));
}

}  // namespace rigcal::monitor
