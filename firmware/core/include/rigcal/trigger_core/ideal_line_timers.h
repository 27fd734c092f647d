// SPDX-License-Identifier: Apache-2.0
#pragma once
// IdealLineTimers: the board's output-compare timers as an ideal model, for host runs of the
// firmware core (the unit tests, drivers' simulated trigger): an armed edge happens exactly at
// its time, when the host run's clock gets there (RunUntil). It refuses to arm an edge at or
// before its clock, as the hardware would miss it. Captures are not simulated (a test calls
// TriggerApp::OnCapture itself). Freestanding, no heap.

#include <cstdint>

#include "rigcal/trigger_core/line_timers.h"

namespace rigcal::trigger_core {

struct LineEdge {
  uint64_t t_us = 0;
  int line = 0;
  bool high = false;
};

// Receives every level change of the model (an armed edge, or a Drive / Release that changed
// the level).
class EdgeSink {
 public:
  virtual void OnEdge(const LineEdge& edge) = 0;

 protected:
  ~EdgeSink() = default;
};

// What the compare interrupt calls (TriggerApp::OnCompare, or a test's adapter).
class CompareHandler {
 public:
  virtual void OnCompare(int line) = 0;

 protected:
  ~CompareHandler() = default;
};

class IdealLineTimers final : public LineTimers {
 public:
  explicit IdealLineTimers(EdgeSink* sink = nullptr) : sink_(sink) {}

  bool Arm(int line, uint64_t t_us, bool high, uint32_t* late_us) override;
  void Drive(int line, bool high) override;
  void Release(int line) override;
  void StartCapture(int line, trigger_protocol::ExposureInput input) override;

  // The model's clock (the µs counter). Setting it makes no edge happen: RunUntil does.
  void set_now(uint64_t now_us) { now_us_ = now_us; }
  uint64_t now() const { return now_us_; }
  // The earliest armed edge, UINT64_MAX when none.
  uint64_t NextEdgeUs() const;
  // Makes every edge armed for `until_us` or earlier happen in time order (the level changed at
  // the edge's time, the clock moved to it unless a handler already moved it further, `handler`
  // told), then sets the clock to `until_us` if it is behind.
  void RunUntil(uint64_t until_us, CompareHandler* handler);

  uint8_t levels() const { return levels_; }
  bool armed(int line) const { return armed_[line].armed; }
  uint64_t armed_us(int line) const { return armed_[line].t_us; }
  trigger_protocol::ExposureInput capture(int line) const { return capture_[line]; }

 private:
  struct Armed {
    bool armed = false;
    uint64_t t_us = 0;
    bool high = false;
  };
  void SetLevel(int line, bool high, uint64_t t_us);

  EdgeSink* sink_;
  uint64_t now_us_ = 0;
  uint8_t levels_ = 0;
  Armed armed_[trigger_protocol::kMaxLines];
  trigger_protocol::ExposureInput capture_[trigger_protocol::kMaxLines] = {};
};

}  // namespace rigcal::trigger_core
