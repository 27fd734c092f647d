// SPDX-License-Identifier: Apache-2.0
#pragma once
// A fake STM32F405 peripheral map for the board code's host build (register_access.h): every
// write is logged in order, reads answer as the reference manual says the hardware would for the
// few behaviours the board code waits on:
//   RCC_CR       HSERDY some reads after HSEON (or never), PLLRDY after PLLON (or never)
//   RCC_CFGR     SWS follows SW once the PLL is ready
//   FLASH_ACR    reads back what was written
//   TIMx_SR      flags clear by writing 0 (rc_w0), set by the test (SetFlag)
//   SysTick CVR  counts down from RVR at the core clock
//   TIM2_CNT     counts at timer_clock_hz / (PSC + 1) while CEN, or as the test sets it
// Time: each register access takes kCyclesPerAccess core cycles (a simple model of a poll loop).
// Reset values as RM0090 gives them (RCC_CR 0x83: HSI on and ready; RCC_PLLCFGR 0x24003010).

#include <cstdint>
#include <map>
#include <vector>

#include "register_access.h"
#include "stm32f405_map.h"

namespace rigcal::testing {

namespace stm32 = ::rigcal::board::stm32;

class FakeStm32 final : public board::RegisterMap {
 public:
  static constexpr uint64_t kCyclesPerAccess = 4;
  static constexpr uint64_t kCoreHz = 168'000'000;

  struct Access {
    uint32_t address;
    uint32_t value;
  };

  // hse_ready_after_reads < 0: the crystal never starts.
  explicit FakeStm32(int hse_ready_after_reads = 100, bool pll_locks = true,
                     uint64_t timer_clock_hz = 84'000'000)
      : hse_after_(hse_ready_after_reads), pll_locks_(pll_locks), timer_hz_(timer_clock_hz) {
    regs_[stm32::kRccCr] = 0x83;
    regs_[stm32::kRccPllCfgr] = 0x24003010;
    board::InstallRegisterMap(this);
  }
  ~FakeStm32() { board::InstallRegisterMap(nullptr); }

  uint32_t Read(uint32_t address) override {
    cycles_ += kCyclesPerAccess;
    ++reads_[address];
    if (address == stm32::kRccCr) return RccCr();
    if (address == stm32::kRccCfgr) {
      const uint32_t sw = regs_[address] & stm32::kRccCfgrSwMask;
      const bool switched = sw != stm32::kRccCfgrSwPll || PllReady();
      return regs_[address] | ((switched ? sw : 0u) << 2);
    }
    if (address == stm32::kSysTickCvr) return SysTickValue();
    if (address == stm32::kTim2 + stm32::kTimCnt) return Tim2Count();
    return regs_[address];
  }
  void Write(uint32_t address, uint32_t value) override {
    cycles_ += kCyclesPerAccess;
    writes_.push_back({address, value});
    if (IsTimer(address) && (address & 0x3FF) == stm32::kTimSr) {
      regs_[address] &= value;  // rc_w0
      return;
    }
    if (address == stm32::kRccCr && (value & stm32::kRccCrHseOn) &&
        !(regs_[address] & stm32::kRccCrHseOn)) {
      hse_on_reads_ = reads_[stm32::kRccCr];
    }
    if (address == stm32::kSysTickCvr) systick_start_ = cycles_;
    if (address == stm32::kTim2 + stm32::kTimCnt || address == stm32::kTim2 + stm32::kTimCr1 ||
        address == stm32::kTim2 + stm32::kTimPsc) {
      tim2_base_ = Tim2Count();
      tim2_since_ = cycles_;
      if (address == stm32::kTim2 + stm32::kTimCnt) tim2_base_ = value;
    }
    regs_[address] = value;
  }

  // The test's own view: no time passes, nothing is logged.
  uint32_t Peek(uint32_t address) const {
    auto it = regs_.find(address);
    return it == regs_.end() ? 0 : it->second;
  }
  void SetFlag(uint32_t timer, uint32_t bits) { regs_[timer + stm32::kTimSr] |= bits; }
  void Poke(uint32_t address, uint32_t value) { regs_[address] = value; }
  // Freezes TIM2's count at `count` (the line-timer tests move it by hand).
  void SetCounter(uint32_t count) {
    manual_counter_ = true;
    regs_[stm32::kTim2 + stm32::kTimCnt] = count;
  }

  const std::vector<Access>& writes() const { return writes_; }
  void ClearWrites() { writes_.clear(); }
  uint64_t reads(uint32_t address) const {
    auto it = reads_.find(address);
    return it == reads_.end() ? 0 : it->second;
  }
  // Index of the first write to `address` whose value has all of `bits` (and none of `none`), or
  // -1.
  int FirstWrite(uint32_t address, uint32_t bits, uint32_t none = 0) const {
    for (size_t i = 0; i < writes_.size(); ++i) {
      const Access& w = writes_[i];
      if (w.address == address && (w.value & bits) == bits && (w.value & none) == 0) {
        return static_cast<int>(i);
      }
    }
    return -1;
  }
  std::vector<uint32_t> ValuesWritten(uint32_t address) const {
    std::vector<uint32_t> out;
    for (const Access& w : writes_) {
      if (w.address == address) out.push_back(w.value);
    }
    return out;
  }

 private:
  static bool IsTimer(uint32_t address) {
    return address >= stm32::kTim2 && address < stm32::kTim5 + 0x400;
  }
  bool PllReady() const { return pll_locks_ && (regs_.at(stm32::kRccCr) & stm32::kRccCrPllOn); }
  uint32_t RccCr() {
    uint32_t v = regs_[stm32::kRccCr] & ~(stm32::kRccCrHseRdy | stm32::kRccCrPllRdy);
    if ((v & stm32::kRccCrHseOn) && hse_after_ >= 0 &&
        reads_[stm32::kRccCr] - hse_on_reads_ > static_cast<uint64_t>(hse_after_)) {
      v |= stm32::kRccCrHseRdy;
    }
    if (PllReady()) v |= stm32::kRccCrPllRdy;
    return v;
  }
  uint32_t SysTickValue() {
    const uint64_t reload = regs_[stm32::kSysTickRvr] & 0xFFFFFF;
    if (!(regs_[stm32::kSysTickCsr] & stm32::kSysTickCsrEnable)) return 0;
    const uint64_t elapsed = cycles_ - systick_start_;
    return static_cast<uint32_t>(reload - elapsed % (reload + 1));
  }
  uint32_t Tim2Count() {
    if (manual_counter_) return regs_[stm32::kTim2 + stm32::kTimCnt];
    if (!(regs_[stm32::kTim2 + stm32::kTimCr1] & stm32::kTimCr1Cen)) return tim2_base_;
    const uint64_t ticks = (cycles_ - tim2_since_) * timer_hz_ / kCoreHz /
                           (uint64_t{regs_[stm32::kTim2 + stm32::kTimPsc]} + 1);
    return static_cast<uint32_t>(tim2_base_ + ticks);
  }

  int hse_after_;
  bool pll_locks_;
  uint64_t timer_hz_;
  uint64_t cycles_ = 0;
  uint64_t hse_on_reads_ = 0;
  uint64_t systick_start_ = 0;
  uint32_t tim2_base_ = 0;
  uint64_t tim2_since_ = 0;
  bool manual_counter_ = false;
  std::map<uint32_t, uint32_t> regs_;
  std::map<uint32_t, uint64_t> reads_;
  std::vector<Access> writes_;
};

}  // namespace rigcal::testing
