#include "hof/app/gui/gui_script.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace hof::app {

namespace {

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

/// Words, with "double quotes" holding spaces (KEY="a b" or "KEY=a b").
std::vector<std::string> quoted_words(const std::string& line) {
  std::vector<std::string> out;
  std::string word;
  bool quoted = false, any = false;
  for (const char c : line) {
    if (c == '"') {
      quoted = !quoted;
      any = true;
    } else if (!quoted && (c == ' ' || c == '\t')) {
      if (any) out.push_back(word);
      word.clear();
      any = false;
    } else {
      word += c;
      any = true;
    }
  }
  if (any) out.push_back(word);
  return out;
}

bool to_number(const std::string& s, double& v) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(v);
}

/// The error of a script line, or "" when it reads.
std::string parse_set(const std::string& line, const std::vector<std::string>& w, ScriptAction& a) {
  a.kind = ScriptAction::Kind::kSet;
  if (w.size() < 3) return "set takes ELEMENT@ATTRIBUTE VALUE, e.g. set haptics/surface@stiffness 0.4";
  const std::size_t at = w[1].find('@');
  if (at == std::string::npos || at == 0 || at + 1 == w[1].size()) {
    return "set takes ELEMENT@ATTRIBUTE VALUE, e.g. set haptics/surface@stiffness 0.4";
  }
  a.element = w[1].substr(0, at);
  a.attribute = w[1].substr(at + 1);
  // The value is the rest of the line (a vector has spaces).
  const std::size_t start = line.find(w[1]) + w[1].size();
  a.value = line.substr(line.find_first_not_of(" \t", start));
  while (!a.value.empty() && (a.value.back() == ' ' || a.value.back() == '\t')) a.value.pop_back();
  return {};
}

std::string parse_edit(const std::string& line, const std::string& verb, ScriptAction& a) {
  a.kind = ScriptAction::Kind::kEdit;
  a.value = verb;
  const std::vector<std::string> q = quoted_words(line);
  const std::size_t fixed = verb == "replace" ? 3 : verb == "add" ? 4 : 2;
  const char* usage = verb == "replace" ? "replace takes mechanics/BODY/COMPONENT TYPE [KEY=VALUE ...]"
                      : verb == "add"   ? "add takes mechanics/BODY TYPE NAME [KEY=VALUE ...]"
                                        : "remove takes mechanics/BODY/COMPONENT";
  if (q.size() < fixed || (verb == "remove" && q.size() != fixed) || !q[1].starts_with("mechanics/")) return usage;
  a.element = q[1];
  const std::size_t slashes = static_cast<std::size_t>(std::count(a.element.begin(), a.element.end(), '/'));
  if (slashes != (verb == "add" ? 1u : 2u)) return usage;
  if (verb != "remove") a.type = q[2];
  if (verb == "add") a.name = q[3];
  for (std::size_t i = fixed; i < q.size(); ++i) {
    const std::size_t eq = q[i].find('=');
    if (eq == std::string::npos || eq == 0) return fmt::format("'{}' is not KEY=VALUE", q[i]);
    a.attributes.emplace_back(q[i].substr(0, eq), q[i].substr(eq + 1));
  }
  return {};
}

std::string parse_region(const std::vector<std::string>& w, ScriptAction& a) {
  a.kind = ScriptAction::Kind::kRegion;
  const char* usage =
      "region takes BODY sphere X Y Z RADIUS YOUNGMODULUS, BODY box X0 Y0 Z0 X1 Y1 Z1 YOUNGMODULUS, or clear";
  if (w.size() == 2 && w[1] == "clear") return {};  // no numbers: every region removed
  if (w.size() < 3 || (w[2] != "sphere" && w[2] != "box")) return usage;
  a.element = w[1];
  a.box = w[2] == "box";
  if (w.size() != (a.box ? 10u : 8u)) return usage;
  for (std::size_t i = 3; i < w.size(); ++i) {
    double v = 0.0;
    if (!to_number(w[i], v)) return fmt::format("'{}' is not a number", w[i]);
    a.numbers.push_back(v);
  }
  return {};
}

std::string parse_tool(const std::vector<std::string>& w, ScriptAction& a) {
  a.kind = ScriptAction::Kind::kTool;
  const char* usage = "tool takes point, needle, sphere RADIUS, capsule LENGTH RADIUS or mesh FILE [RADIUS] (metres)";
  if (w.size() < 2) return usage;
  a.type = w[1];
  std::size_t first_number = 2;
  if (a.type == "mesh") {
    if (w.size() < 3) return usage;
    a.file = w[2];
    first_number = 3;
  }
  const std::size_t expected = a.type == "point" || a.type == "needle" ? 2
                               : a.type == "sphere"                    ? 3
                               : a.type == "capsule"                   ? 4
                               : a.type == "mesh"                      ? (w.size() == 4 ? 4 : 3)
                                                                       : 0;
  if (expected == 0 || w.size() != expected) return usage;
  for (std::size_t i = first_number; i < w.size(); ++i) {
    double v = 0.0;
    if (!to_number(w[i], v) || v < 0.0) return fmt::format("'{}' is not a length in metres (>= 0)", w[i]);
    a.numbers.push_back(v);
  }
  return {};
}

std::string parse_action(const std::string& line, const std::vector<std::string>& w, ScriptAction& a) {
  const std::string& verb = w[0];
  if (verb == "wait") {
    a.kind = ScriptAction::Kind::kWait;
    if (w.size() != 2 || !to_number(w[1], a.number) || a.number < 0.0 || a.number > 3600.0) {
      return "wait takes seconds in [0, 3600]";
    }
  } else if (verb == "needle") {
    a.kind = ScriptAction::Kind::kNeedle;
    if (w.size() != 2 || (w[1] != "on" && w[1] != "off")) return "needle takes on or off";
    a.on = w[1] == "on";
  } else if (verb == "tool") {
    return parse_tool(w, a);
  } else if (verb == "rotate") {
    a.kind = ScriptAction::Kind::kRotate;
    const char* usage = "rotate takes an axis X Y Z (not zero) and an angle in degrees";
    if (w.size() != 5) return usage;
    for (std::size_t i = 1; i < 5; ++i) {
      double v = 0.0;
      if (!to_number(w[i], v)) return usage;
      a.numbers.push_back(v);
    }
    if (a.numbers[0] == 0.0 && a.numbers[1] == 0.0 && a.numbers[2] == 0.0) return usage;
  } else if (verb == "contacts") {
    a.kind = ScriptAction::Kind::kContacts;
    if (w.size() != 2 || (w[1] != "on" && w[1] != "off")) return "contacts takes on or off (the debug view)";
    a.on = w[1] == "on";
  } else if (verb == "pair") {
    a.kind = ScriptAction::Kind::kPair;
    if (w.size() != 4 || (w[3] != "on" && w[3] != "off")) return "pair takes two bodies and on or off";
    a.element = w[1];
    a.attribute = w[2];
    a.on = w[3] == "on";
  } else if (verb == "animate") {
    a.kind = ScriptAction::Kind::kAnimate;
    if (w.size() != 2 || (w[1] != "on" && w[1] != "off")) return "animate takes on or off";
    a.on = w[1] == "on";
  } else if (verb == "step") {
    a.kind = ScriptAction::Kind::kStep;
    a.number = 1.0;
    if (w.size() > 2 || (w.size() == 2 && (!to_number(w[1], a.number) || a.number < 1.0 || a.number > 1e6 ||
                                           a.number != std::floor(a.number)))) {
      return "step takes a number of steps in [1, 1000000]";
    }
  } else if (verb == "reset") {
    a.kind = ScriptAction::Kind::kReset;
    if (w.size() != 1) return "reset takes nothing";
  } else if (verb == "set") {
    return parse_set(line, w, a);
  } else if (verb == "replace" || verb == "add" || verb == "remove") {
    return parse_edit(line, verb, a);
  } else if (verb == "region") {
    return parse_region(w, a);
  } else if (verb == "mouse") {
    a.kind = ScriptAction::Kind::kMouse;
    if (w.size() < 3 || w.size() > 4 || !to_number(w[1], a.number) || !to_number(w[2], a.y) ||
        (w.size() == 4 && !to_number(w[3], a.depth))) {
      return "mouse takes X Y [DEPTH]: window pixels and metres beyond the touch plane";
    }
  } else if (verb == "open") {
    a.kind = ScriptAction::Kind::kOpen;
    if (w.size() != 2) return "open takes one file name (no spaces)";
    a.file = w[1];
  } else if (verb == "show") {
    a.kind = ScriptAction::Kind::kShow;
    if (w.size() != 2 || (w[1] != "tool" && w[1] != "contacts" && w[1] != "needle" && w[1] != "mechanics" &&
                          w[1] != "haptics" && w[1] != "graphics" && w[1] != "messages")) {
      return "show takes a panel: tool, contacts, needle, mechanics, haptics, graphics or messages";
    }
    a.value = w[1];
  } else if (verb == "record") {
    a.kind = ScriptAction::Kind::kRecord;
    if (w.size() != 2) return "record takes FILE.csv (start) or off (stop and write)";
    a.on = w[1] != "off";
    if (a.on) {
      a.file = w[1];
      if (a.file.extension() != ".csv") return "a recording is a .csv file (the replay format)";
    }
  } else if (verb == "screenshot" || verb == "save") {
    a.kind = verb == "save" ? ScriptAction::Kind::kSave : ScriptAction::Kind::kScreenshot;
    if (w.size() != 2) return verb + " takes one file name (no spaces)";
    a.file = w[1];
    const std::string ext = a.file.extension().string();
    if (verb == "screenshot" && ext != ".png") return "a screenshot is a .png file";
    if (verb == "save" && ext != ".hof") return "a project is saved as a .hof file";
  } else if (verb == "quit") {
    a.kind = ScriptAction::Kind::kQuit;
    if (w.size() != 1) return "quit takes nothing";
  } else {
    return fmt::format(
        "unknown action '{}' (known: wait, animate, step, needle, tool, rotate, contacts, pair, reset, set, replace, "
        "add, remove, region, mouse, open, show, record, screenshot, save, quit)",
        verb);
  }
  return {};
}

}  // namespace

Expected<std::vector<ScriptAction>> parse_script(const std::string& text, const std::string& name) {
  std::vector<ScriptAction> actions;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::vector<std::string> w = words(line);
    if (w.empty() || w[0].starts_with('#')) continue;
    ScriptAction a;
    a.line = number;
    a.text = line;
    if (const std::string error = parse_action(line, w, a); !error.empty()) {
      return make_error(ErrorCode::kParse, fmt::format("'{}': {}", line, error), name, number);
    }
    actions.push_back(std::move(a));
  }
  return actions;
}

Expected<std::vector<ScriptAction>> read_script(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIo, "cannot open the script", path.string());
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse_script(buffer.str(), path.string());
}

}  // namespace hof::app
