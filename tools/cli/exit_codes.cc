// SPDX-License-Identifier: Apache-2.0
#include "exit_codes.h"

#include <iostream>

namespace rigcal::cli {

int PrintCommandError(std::string_view command, std::string_view message) {
  std::cerr << "rigcal " << command << ": " << message << "\n";
  return kExitError;
}

}  // namespace rigcal::cli
