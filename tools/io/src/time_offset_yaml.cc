// SPDX-License-Identifier: Apache-2.0
// `estimator.time_offset` of a rig config: auto, seconds, or per slave.
#include <cmath>
#include <string>
#include <vector>

#include "config_sections.h"
#include "yaml_fields.h"

namespace rigcal::io {
namespace {

constexpr double kMaxOffsetS = 86400.0;
const char kField[] = "estimator.time_offset";

// nullopt for auto, else the offset in seconds.
Expected<std::optional<double>> OffsetValue(const FieldReader& r, const YAML::Node& node,
                                            const std::string& field) {
  if (!node.IsScalar()) return r.Fail(node, field, "must be auto or a number of seconds");
  if (node.Scalar() == "auto") return std::optional<double>();
  auto v = r.Number(node, field);
  if (!v)
    return r.Fail(node, field, "must be auto or a number of seconds, got '" + node.Scalar() + "'");
  if (!(std::abs(*v) <= kMaxOffsetS)) {
    return r.Fail(node, field, "must be in [-86400, 86400] s, got " + node.Scalar());
  }
  return std::optional<double>(*v);
}

}  // namespace

Expected<ClockOffsetOptions> ParseTimeOffsetSection(const YAML::Node& node,
                                                    const std::vector<std::string>& slave_names,
                                                    const std::string& master,
                                                    const std::string& path) {
  const FieldReader r(path);
  ClockOffsetOptions options;
  options.enabled = true;
  if (!node.IsMap()) {
    auto value = OffsetValue(r, node, kField);
    if (!value) return Error{value.error()};
    options.given_s.assign(slave_names.size(), *value);
    return options;
  }
  options.given_s.assign(slave_names.size(), std::nullopt);
  std::vector<bool> seen(slave_names.size(), false);
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string name = it->first.Scalar();
    const std::string field = std::string(kField) + "." + name;
    if (name == master) {
      return r.Fail(it->first, field, "the master's clock is the reference: only slaves have one");
    }
    size_t i = 0;
    while (i < slave_names.size() && slave_names[i] != name) ++i;
    if (i == slave_names.size()) return r.Fail(it->first, field, "not a camera of the rig");
    if (seen[i]) return r.Fail(it->first, field, "given twice");
    seen[i] = true;
    auto value = OffsetValue(r, it->second, field);
    if (!value) return Error{value.error()};
    options.given_s[i] = *value;
  }
  return options;
}

}  // namespace rigcal::io
