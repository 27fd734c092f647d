// SPDX-License-Identifier: Apache-2.0
#include "yaml_fields.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/io/camera_name.h"
#include "rigcal/io/text_file.h"

namespace rigcal::io {

namespace {

// "<path>:<line>: " of a node.
std::string Where(const std::string& path, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? path + ": " : path + ":" + std::to_string(mark.line + 1) + ": ";
}

// Most nodes DuplicateKey visits, counting a node each time an alias reaches it: a few hundred
// bytes of nested aliases ("billion laughs") stand for 10^9 nodes, which no rigcal file has.
constexpr int64_t kMaxVisitedNodes = 100'000;

// The first key that appears twice in a map of `node` (at any depth): yaml-cpp keeps both, and
// a lookup would silently use one of them. `*budget`: nodes left to visit.
std::optional<Error> DuplicateKey(const std::string& path, const YAML::Node& node, int depth,
                                  int64_t* budget) {
  if (depth > 64) return std::nullopt;  // yaml-cpp itself limits the nesting far below
  if (--*budget < 0) {
    return Error{path + ": more than " + std::to_string(kMaxVisitedNodes) +
                 " YAML nodes with every alias expanded (nested aliases?): not a rigcal file"};
  }
  if (node.IsMap()) {
    std::set<std::string> keys;
    for (auto it = node.begin(); it != node.end(); ++it) {
      if (it->first.IsScalar() && !keys.insert(it->first.Scalar()).second) {
        return Error{Where(path, it->first) + it->first.Scalar() +
                     ": duplicate key (each key may appear once in a map)"};
      }
      if (auto e = DuplicateKey(path, it->second, depth + 1, budget)) return e;
    }
  } else if (node.IsSequence()) {
    for (const YAML::Node& child : node) {
      if (auto e = DuplicateKey(path, child, depth + 1, budget)) return e;
    }
  }
  return std::nullopt;
}

// Remembers where each document's first node is (the start of the document when it has none);
// ignores everything else.
class DocumentStarts : public YAML::EventHandler {
 public:
  std::vector<YAML::Mark> starts;
  std::vector<YAML::Mark> first_nodes;
  void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { Node(mark); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { Node(mark); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string&) override {
    Node(mark);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    Node(mark);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    Node(mark);
  }
  void OnMapEnd() override {}

 private:
  void Node(const YAML::Mark& mark) {
    if (first_nodes.size() < starts.size()) first_nodes.push_back(mark);
  }
};

// The start of a second document in `text`, if there is one. At most two documents are parsed:
// YAML::LoadAll loops forever on some malformed input (yaml-cpp 0.7 makes an endless series of
// empty documents of "," and a broken line; found by the rig_yaml fuzz target).
std::optional<YAML::Mark> SecondDocument(const std::string& text) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentStarts documents;
  if (!parser.HandleNextDocument(documents)) return std::nullopt;
  if (!parser.HandleNextDocument(documents)) return std::nullopt;
  if (documents.first_nodes.size() >= 2) return documents.first_nodes[1];
  return documents.starts.size() >= 2 ? documents.starts[1] : YAML::Mark::null_mark();
}

// The first line at or after `line` (0-based) that holds content: yaml-cpp marks a document's
// first node at its `---` line when the content starts on the next one.
int ContentLine(const std::string& text, int line) {
  std::istringstream in(text);
  std::string row;
  for (int i = 0; std::getline(in, row); ++i) {
    if (i < line) continue;
    const size_t begin = row.find_first_not_of(" \t\r");
    if (begin == std::string::npos || row[begin] == '#') continue;
    if (row.compare(begin, 3, "---") == 0) {
      const size_t rest = row.find_first_not_of(" \t\r", begin + 3);
      if (rest == std::string::npos || row[rest] == '#') continue;
    }
    return i;
  }
  return line;
}

}  // namespace

Expected<YAML::Node> LoadYaml(const std::string& path) {
  auto text = ReadWholeFile(path);
  if (!text) return Error{text.error()};
  try {
    if (const std::optional<YAML::Mark> second = SecondDocument(*text)) {
      return Error{
          (second->is_null()
               ? path + ": "
               : path + ":" + std::to_string(ContentLine(*text, second->line) + 1) + ": ") +
          "a second YAML document (after ---): the file must hold one document"};
    }
    const YAML::Node root = YAML::Load(*text);
    int64_t budget = kMaxVisitedNodes;
    if (auto e = DuplicateKey(path, root, 0, &budget)) return *e;
    return root;
  } catch (const YAML::ParserException& e) {
    return Error{path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg};
  } catch (const YAML::Exception& e) {
    return Error{path + ": YAML error: " + e.what()};
  }
}

std::string FieldReader::At(const YAML::Node& node) const { return Where(path_, node); }

Error FieldReader::Fail(const YAML::Node& node, const std::string& field,
                        const std::string& what) const {
  return Error{At(node) + field + ": " + what};
}

Expected<double> FieldReader::Number(const YAML::Node& node, const std::string& field) const {
  if (!node.IsScalar()) return Fail(node, field, "expected a number");
  const std::string& text = node.Scalar();
  std::string_view view(text);
  if (view.size() > 1 && view[0] == '+') view.remove_prefix(1);
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(view.data(), view.data() + view.size(), value);
  if (view.empty() || ec != std::errc() || ptr != view.data() + view.size()) {
    return Fail(node, field, "'" + text + "' is not a number");
  }
  if (!std::isfinite(value)) return Fail(node, field, "'" + text + "' is not finite");
  return value;
}

Expected<int> FieldReader::Integer(const YAML::Node& node, const std::string& field) const {
  if (!node.IsScalar()) return Fail(node, field, "expected an integer");
  const std::string& text = node.Scalar();
  int value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size()) {
    return Fail(node, field, "'" + text + "' is not an integer");
  }
  return value;
}

Expected<int64_t> FieldReader::Integer64(const YAML::Node& node, const std::string& field) const {
  if (!node.IsScalar()) return Fail(node, field, "expected an integer");
  const std::string& text = node.Scalar();
  int64_t value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size()) {
    return Fail(node, field, "'" + text + "' is not an integer");
  }
  return value;
}

Expected<bool> FieldReader::Bool(const YAML::Node& node, const std::string& field) const {
  if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    if (text == "true" || text == "yes" || text == "on") return true;
    if (text == "false" || text == "no" || text == "off") return false;
  }
  return Fail(node, field, "expected true or false");
}

Expected<std::string> FieldReader::String(const YAML::Node& node, const std::string& field) const {
  if (!node.IsScalar() || node.Scalar().empty()) return Fail(node, field, "expected a string");
  return node.Scalar();
}

Expected<std::string> FieldReader::CameraName(const YAML::Node& node,
                                              const std::string& field) const {
  auto name = String(node, field);
  if (!name) return name;
  if (const std::string problem = CameraNameProblem(*name); !problem.empty()) {
    return Fail(node, field, problem);
  }
  return name;
}

Expected<std::vector<double>> FieldReader::Numbers(const YAML::Node& parent, const std::string& key,
                                                   const std::string& field, size_t n) const {
  const YAML::Node node = parent[key];
  if (!node) return Fail(parent, field, "missing (expected " + std::to_string(n) + " numbers)");
  return NumbersOf(node, field, n);
}

Expected<std::vector<double>> FieldReader::NumbersOf(const YAML::Node& node,
                                                     const std::string& field, size_t n) const {
  if (!node.IsSequence()) {
    return Fail(node, field, "expected a list of " + std::to_string(n) + " numbers");
  }
  if (node.size() != n) {
    return Fail(node, field,
                "expected " + std::to_string(n) + " numbers, got " + std::to_string(node.size()));
  }
  return NumberList(node, field, n);
}

Expected<Eigen::Quaterniond> FieldReader::UnitQuaternion(const YAML::Node& parent,
                                                         const std::string& key,
                                                         const std::string& field) const {
  constexpr double kNormTolerance = 1e-3;
  auto q = Numbers(parent, key, field, 4);
  if (!q) return Error{q.error()};
  const Eigen::Vector4d wxyz((*q)[0], (*q)[1], (*q)[2], (*q)[3]);
  const double norm = wxyz.norm();
  if (!(std::abs(norm - 1.0) <= kNormTolerance)) {
    return Fail(parent[key], field,
                "norm " + SignificantText(norm, 6) + " is not 1 within " +
                    SignificantText(kNormTolerance, 6));
  }
  return Eigen::Quaterniond(wxyz[0] / norm, wxyz[1] / norm, wxyz[2] / norm, wxyz[3] / norm);
}

Expected<std::vector<double>> FieldReader::NumberList(const YAML::Node& node,
                                                      const std::string& field,
                                                      size_t min_n) const {
  if (!node.IsSequence()) return Fail(node, field, "expected a list of numbers");
  if (node.size() < min_n) {
    return Fail(node, field,
                "expected at least " + std::to_string(min_n) + " numbers, got " +
                    std::to_string(node.size()));
  }
  std::vector<double> values;
  values.reserve(node.size());
  for (size_t i = 0; i < node.size(); ++i) {
    auto v = Number(node[i], field + "[" + std::to_string(i) + "]");
    if (!v) return Error{v.error()};
    values.push_back(*v);
  }
  return values;
}

std::optional<Error> FieldReader::CheckKeys(const YAML::Node& node, const std::string& prefix,
                                            const std::set<std::string>& known) const {
  if (!node.IsMap()) return Fail(node, prefix.empty() ? "(top level)" : prefix, "expected a map");
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = it->first.Scalar();
    if (known.count(key) == 0) {
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      return Fail(it->first, prefix + key, "unknown key; expected one of " + list);
    }
  }
  return std::nullopt;
}

}  // namespace rigcal::io
