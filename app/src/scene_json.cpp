#include <cmath>
#include <limits>
#include <set>
#include <unordered_map>
#include <vector>

#include "scene_reader.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app::scene {

std::string Brief(const json& j) {
  std::string text = j.dump(-1, ' ', true, json::error_handler_t::replace);
  if (text.size() > kMaxEcho) text = text.substr(0, kMaxEcho - 3) + "...";
  return text;
}

std::string Shown(const std::string& key) { return ShowText(key, kMaxEcho); }

bool Printable(const std::string& text) { return IsPlainText(text); }

Status StructureScan::Run(const std::string& origin) {
  struct Frame {
    bool object;
    std::string path;
    std::unordered_map<std::string, int> keys;  // key -> its line (a map: an object may have 100,000 keys)
    std::string pendingKey;
    size_t index = 0;
  };
  std::vector<Frame> stack;
  int line = 1;
  auto childPath = [&]() -> std::string {
    if (stack.empty()) return "";
    const Frame& f = stack.back();
    if (f.object) return f.path.empty() ? f.pendingKey : f.path + "." + f.pendingKey;
    return f.path + "[" + std::to_string(f.index) + "]";
  };
  for (size_t i = 0; i < m_text.size(); ++i) {
    const char c = m_text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '"') {
      const size_t start = i;
      for (++i; i < m_text.size() && m_text[i] != '"'; ++i) {
        if (m_text[i] == '\\') ++i;
      }
      if (stack.empty() || !stack.back().object) continue;
      // A key is a string followed by ':'.
      size_t k = i + 1;
      while (k < m_text.size() && (m_text[k] == ' ' || m_text[k] == '\t' || m_text[k] == '\r' || m_text[k] == '\n')) ++k;
      if (k >= m_text.size() || m_text[k] != ':') continue;
      std::string key = m_text.substr(start + 1, i - start - 1);
      if (key.find('\\') != std::string::npos) {  // escapes: compare keys as the parser reads them
        try {
          key = json::parse(m_text.substr(start, i - start + 1)).get<std::string>();
        } catch (const json::exception&) {
        }
      }
      Frame& f = stack.back();
      if (const auto seen = f.keys.find(key); seen != f.keys.end()) {
        const std::string where = f.path.empty() ? "at the top level" : "in " + Shown(f.path);
        return Status::Error(Format("%s: key %s appears twice %s (lines %d and %d): the second would replace the "
                                    "first; keep one",
                                    origin.c_str(), Brief(json(key)).c_str(), where.c_str(), seen->second, line));
      }
      f.keys.emplace(key, line);
      f.pendingKey = key;
    } else if (c == '{' || c == '[') {
      if (static_cast<int>(stack.size()) >= kMaxDepth) {
        return Status::Error(Format("%s: line %d: nested more than %d levels deep: not a scene", origin.c_str(), line,
                                    kMaxDepth));
      }
      Frame f;
      f.object = c == '{';
      f.path = childPath();
      stack.push_back(std::move(f));
    } else if (c == '}' || c == ']') {
      if (!stack.empty()) stack.pop_back();
    } else if (c == ',' && !stack.empty() && !stack.back().object) {
      ++stack.back().index;
    }
  }
  return Status::Ok();
}

Status Reader::Error(const std::string& key, const std::string& why) const {
  return Status::Error(m_out->path + ": " + key + ": " + why);
}

void Reader::CheckKeys(const json& obj, const std::string& prefix, std::initializer_list<const char*> known) {
  std::set<std::string> names(known.begin(), known.end());
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (!names.count(it.key())) {
      const std::string key = prefix.empty() ? Shown(it.key()) : prefix + "." + Shown(it.key());
      Unknown(key);
    }
  }
}

void Reader::Unknown(const std::string& key) {
  if (++m_unknown > kMaxWarnings) return;
  m_out->warnings.push_back("unknown key '" + key + "' ignored");
  SPHXR_LOG_WARN("%s: unknown key '%s' ignored", m_out->path.c_str(), key.c_str());
}

void Reader::CountUnknown() const {
  if (m_unknown <= kMaxWarnings) return;
  m_out->warnings.push_back(Format("%d more unknown keys ignored", m_unknown - kMaxWarnings));
  SPHXR_LOG_WARN("%s: %d more unknown keys ignored", m_out->path.c_str(), m_unknown - kMaxWarnings);
}

Status Reader::Number(const json& j, const std::string& key, double* v) const {
  if (!j.is_number()) return Error(key, "must be a number, got " + std::string(j.type_name()) + " " + Brief(j));
  *v = j.get<double>();
  if (!std::isfinite(*v)) return Error(key, "must be finite");
  // Every scene number is stored as a float: beyond its range the conversion is undefined.
  if (std::fabs(*v) > static_cast<double>(std::numeric_limits<float>::max())) {
    return Error(key, "is " + Brief(j) + ", beyond the range of a float (3.4e38)");
  }
  return Status::Ok();
}

Status Reader::Vec(const json& j, const std::string& key, sim::Vec3* v) const {
  if (!j.is_array() || j.size() != 3) return Error(key, "must be an array of three numbers, got " + Brief(j));
  double c[3];
  for (int i = 0; i < 3; ++i) {
    if (Status s = Number(j[i], key + "[" + std::to_string(i) + "]", &c[i]); !s) return s;
  }
  *v = sim::Vec3{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
  return Status::Ok();
}

Status Reader::Box(const json& j, const std::string& key, sim::Aabb* box) const {
  if (!j.contains("min") || !j.contains("max")) return Error(key, "needs \"min\" and \"max\"");
  if (Status s = Vec(j["min"], key + ".min", &box->min); !s) return s;
  if (Status s = Vec(j["max"], key + ".max", &box->max); !s) return s;
  return Status::Ok();
}

}  // namespace sphxr::app::scene
