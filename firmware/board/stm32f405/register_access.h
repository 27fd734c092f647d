// SPDX-License-Identifier: Apache-2.0
#pragma once
// How the board code reaches the peripherals. On the MCU: volatile loads and stores at the
// RM0090 addresses. In the host build (RIGCAL_BOARD_HOST, the tests' rigcal_trigger_board_host
// library): every access goes to the RegisterMap the test installed, a fake peripheral map that
// records the writes and answers the reads (tests/firmware/fake_stm32.h), so the same board code
// is checked against the reference manual's values without hardware.

#include <cstdint>

namespace rigcal::board {

#if defined(RIGCAL_BOARD_HOST)
class RegisterMap {
 public:
  virtual uint32_t Read(uint32_t address) = 0;
  virtual void Write(uint32_t address, uint32_t value) = 0;

 protected:
  ~RegisterMap() = default;
};
// The map every access goes to (host build only); a test installs it before calling board code.
void InstallRegisterMap(RegisterMap* map);
RegisterMap* InstalledRegisterMap();
inline uint32_t Read32(uint32_t address) { return InstalledRegisterMap()->Read(address); }
inline void Write32(uint32_t address, uint32_t value) {
  InstalledRegisterMap()->Write(address, value);
}
#else
inline uint32_t Read32(uint32_t address) { return *reinterpret_cast<volatile uint32_t*>(address); }
inline void Write32(uint32_t address, uint32_t value) {
  *reinterpret_cast<volatile uint32_t*>(address) = value;
}
#endif

inline void Set32(uint32_t address, uint32_t bits) { Write32(address, Read32(address) | bits); }
inline void Clear32(uint32_t address, uint32_t bits) { Write32(address, Read32(address) & ~bits); }
// Replaces the `mask` bits of a register with `value` (already shifted).
inline void Modify32(uint32_t address, uint32_t mask, uint32_t value) {
  Write32(address, (Read32(address) & ~mask) | (value & mask));
}

}  // namespace rigcal::board
