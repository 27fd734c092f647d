// SPDX-License-Identifier: Apache-2.0
#include "service_unit.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>

namespace rigcal::device_test {
namespace {

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::string Lookup(const std::map<std::string, std::string>& environment, const std::string& key) {
  const auto it = environment.find(key);
  return it == environment.end() ? std::string() : it->second;
}

std::vector<std::string> SplitWords(const std::string& text) {
  std::vector<std::string> words;
  std::istringstream in(text);
  for (std::string word; in >> word;) words.push_back(word);
  return words;
}

}  // namespace

std::vector<std::string> ServiceUnit::ExpandExecStart(
    const std::map<std::string, std::string>& env) const {
  std::string line = exec_start;
  while (!line.empty() && std::string("@-:+!").find(line[0]) != std::string::npos) {
    line.erase(0, 1);
  }
  static const std::regex braced(R"(\$\{([A-Za-z_][A-Za-z0-9_]*)\})");
  static const std::regex bare(R"(^\$([A-Za-z_][A-Za-z0-9_]*)$)");
  std::vector<std::string> words;
  for (const std::string& word : SplitWords(line)) {
    std::smatch m;
    if (std::regex_match(word, m, bare)) {  // $VAR alone: split into words, none when empty
      for (const std::string& w : SplitWords(Lookup(env, m[1].str()))) words.push_back(w);
      continue;
    }
    std::string expanded;
    auto begin = word.cbegin();
    for (std::sregex_iterator it(word.begin(), word.end(), braced), end; it != end; ++it) {
      expanded.append(begin, word.cbegin() + it->position()) += Lookup(env, (*it)[1].str());
      begin = word.cbegin() + it->position() + it->length();
    }
    words.push_back(expanded.append(begin, word.cend()));
  }
  return words;
}

Expected<ServiceUnit> ReadServiceUnit(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error{path + ": cannot be read"};
  ServiceUnit unit;
  std::string section;
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    line = Trim(line);
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line.front() == '[' && line.back() == ']') {
      section = line;
      continue;
    }
    const size_t eq = line.find('=');
    if (eq == std::string::npos || line.back() == '\\') {
      return Error{path + ":" + std::to_string(number) + ": not a Key=value line: " + line};
    }
    if (section != "[Service]") continue;
    const std::string key = Trim(line.substr(0, eq));
    const std::string value = Trim(line.substr(eq + 1));
    if (key == "Environment") {
      for (const std::string& assignment : SplitWords(value)) {
        const size_t e = assignment.find('=');
        if (e == std::string::npos || assignment.find('"') != std::string::npos) {
          return Error{path + ":" + std::to_string(number) + ": Environment=: " + assignment};
        }
        unit.environment[assignment.substr(0, e)] = assignment.substr(e + 1);
      }
    } else if (key == "ExecStart") {
      if (!unit.exec_start.empty()) {
        return Error{path + ":" + std::to_string(number) + ": a second ExecStart="};
      }
      unit.exec_start = value;
    } else {
      unit.settings[key] = value;
    }
  }
  if (unit.exec_start.empty()) return Error{path + ": no ExecStart= in [Service]"};
  return unit;
}

double SystemdSpanSeconds(const std::string& span) {
  static const std::regex part(R"(\s*([0-9]+(?:\.[0-9]+)?)\s*(ms|s|sec|min|m|h)?)");
  double seconds = 0.0;
  size_t at = 0;
  for (std::smatch m; at < span.size();) {
    const std::string rest = span.substr(at);
    if (!std::regex_search(rest, m, part, std::regex_constants::match_continuous) ||
        m.length() == 0) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    const std::string unit = m[2].str();
    const double factor = unit == "ms"                   ? 1e-3
                          : unit == "min" || unit == "m" ? 60.0
                          : unit == "h"                  ? 3600.0
                                                         : 1.0;
    seconds += std::stod(m[1].str()) * factor;
    at += m.length();
  }
  return at == 0 ? std::numeric_limits<double>::quiet_NaN() : seconds;
}

}  // namespace rigcal::device_test
