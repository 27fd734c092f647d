// SPDX-License-Identifier: Apache-2.0
#pragma once
// The provenance (io/provenance.h) of what a command writes: this rigcal, now, its command line
// and its input files.

#include <string>
#include <vector>

#include "rigcal/io/provenance.h"

namespace rigcal::cli {

// `inputs`: the files read (empty entries are skipped); `config`: the rig config, or empty;
// `metric`: the result's C in metres.
io::Provenance ProvenanceOf(const std::vector<std::string>& inputs, const std::string& config,
                            bool metric);

}  // namespace rigcal::cli
