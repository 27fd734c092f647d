// SPDX-License-Identifier: Apache-2.0
#include "command_line.h"

#include <algorithm>
#include <atomic>

namespace rigcal::cli {
namespace {

std::atomic<bool> quiet_requested{false};
std::string& VersionText() {
  static std::string text;
  return text;
}
std::string& CommandText() {
  static std::string text;
  return text;
}

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// Every name an option of `app` answers to ("--master", "-o"), with its parents' (the main
// app's options are accepted after the subcommand too).
std::vector<std::string> OptionNames(const CLI::App* app) {
  std::vector<std::string> names = {"--help", "-h"};
  for (; app != nullptr; app = app->get_parent()) {
    for (const CLI::Option* option : app->get_options()) {
      for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
      for (const std::string& name : option->get_snames()) names.push_back("-" + name);
    }
  }
  return names;
}

std::string Suggestion(const std::string& word, const std::vector<std::string>& names) {
  const std::string near = NearestName(word, names);
  return near.empty() ? "" : "; did you mean '" + near + "'?";
}

// The option word without an attached value ("--out=x" -> "--out").
std::string OptionName(const std::string& word) {
  const size_t eq = word.find('=');
  return word.rfind("--", 0) == 0 && eq != std::string::npos ? word.substr(0, eq) : word;
}

}  // namespace

Verbosity ExtractVerbosity(std::vector<std::string>* args) {
  Verbosity v;
  std::vector<std::string> kept;
  for (size_t i = 0; i < args->size(); ++i) {
    const std::string& word = (*args)[i];
    if (word == "--") {
      kept.insert(kept.end(), args->begin() + static_cast<long>(i), args->end());
      break;
    }
    if (word == "-q" || word == "--quiet") {
      v.log_level = "warn";
      v.quiet = true;
    } else if (word == "-v" || word == "--verbose") {
      v.log_level = "debug";
      v.quiet = false;
    } else if (word.rfind("--log-level=", 0) == 0) {
      v.log_level = word.substr(12);
    } else if (word == "--log-level" && i + 1 < args->size()) {
      v.log_level = (*args)[++i];
    } else {
      kept.push_back(word);
    }
  }
  *args = std::move(kept);
  return v;
}

void SetInvocation(const std::string& version, int argc, char** argv) {
  VersionText() = version;
  std::string command = "rigcal";
  for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
  CommandText() = command;
}
const std::string& RigcalVersion() { return VersionText(); }
const std::string& CommandLine() { return CommandText(); }

bool QuietRequested() { return quiet_requested.load(); }
void SetQuietRequested(bool quiet) { quiet_requested.store(quiet); }

std::string NearestName(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_distance = std::max<size_t>(2, word.size() / 3) + 1;
  for (const std::string& candidate : candidates) {
    const size_t d = EditDistance(word, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

std::string UnknownWordError(const CLI::App& app, const std::vector<std::string>& args) {
  const CLI::App* sub = nullptr;
  std::vector<std::string> subcommands;
  for (const CLI::App* s : app.get_subcommands({})) subcommands.push_back(s->get_name());
  for (const std::string& word : args) {
    if (word == "--") break;
    if (word.empty() || word[0] != '-' || word == "-") {
      // A subcommand of the current one (`import euroc`), else a positional argument or an
      // option's value once a subcommand is known.
      const CLI::App* next = nullptr;
      for (const CLI::App* s : (sub != nullptr ? sub : &app)->get_subcommands({})) {
        if (s->check_name(word)) next = s;
      }
      if (next != nullptr) {
        sub = next;
        continue;
      }
      if (sub == nullptr) {
        return "rigcal: unknown subcommand '" + word + "'" + Suggestion(word, subcommands) +
               " (rigcal --help lists them)";
      }
      continue;
    }
    const std::vector<std::string> names = OptionNames(sub != nullptr ? sub : &app);
    const std::string name = OptionName(word);
    // A negative number is a value ("--offset -0.5"); "-abc" may be stacked short flags.
    if (name.size() >= 2 && (std::isdigit(static_cast<unsigned char>(name[1])) || name[1] == '.')) {
      continue;
    }
    if (name.rfind("--", 0) != 0) continue;
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      const std::string who = sub != nullptr ? "rigcal " + sub->get_name() : "rigcal";
      return who + ": unknown option '" + name + "'" + Suggestion(name, names) + " (" + who +
             " --help lists them)";
    }
  }
  return "";
}

}  // namespace rigcal::cli
