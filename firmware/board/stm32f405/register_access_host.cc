// SPDX-License-Identifier: Apache-2.0
// The host build's register map (register_access.h): tests install a fake peripheral map.
#include "register_access.h"

namespace rigcal::board {
namespace {
RegisterMap* g_map = nullptr;
}  // namespace

void InstallRegisterMap(RegisterMap* map) { g_map = map; }
RegisterMap* InstalledRegisterMap() { return g_map; }

}  // namespace rigcal::board
