#pragma once
// The bytes of a state file (sphxr/app/state_file.h describes the layout): its magic, byte order and
// versions, and the writer and reader of its fields. Private to state_file.cpp.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "sphxr/sim/rigid.h"

namespace sphxr::app::state_format {

inline constexpr char kMagic[8] = {'S', 'P', 'H', 'X', 'R', 'S', 'T', '1'};
inline constexpr uint32_t kByteOrder = 0x01020304u;
// 2: the step count after the clock; 3: the solver method after the scene name; 4: the diffuse particles
// after the fields
inline constexpr uint32_t kVersion = 4;
inline constexpr uint32_t kOldestVersion = 1;
static_assert(sizeof(sim::Vec3) == 12 && sizeof(sim::Quat) == 16 && sizeof(sim::Pose) == 28,
              "state files write these structs as their bytes: they must have no padding");

class Writer {
 public:
  explicit Writer(std::ofstream* out) : m_out(out) {}
  void Bytes(const void* p, size_t n) {
    if (n > 0) m_out->write(static_cast<const char*>(p), static_cast<std::streamsize>(n));
  }
  template <class T>
  void Put(const T& v) {
    Bytes(&v, sizeof(T));
  }
  void String(const std::string& s) {
    Put(static_cast<uint32_t>(s.size()));
    Bytes(s.data(), s.size());
  }

 private:
  std::ofstream* m_out;
};

class Reader {
 public:
  explicit Reader(std::vector<char> data) : m_data(std::move(data)) {}
  bool Bytes(void* p, size_t n) {
    if (n == 0) return true;  // (no memcpy with an empty field's null pointer)
    if (n > m_data.size() - m_at) return false;
    std::memcpy(p, m_data.data() + m_at, n);
    m_at += n;
    return true;
  }
  template <class T>
  bool Get(T* v) {
    return Bytes(v, sizeof(T));
  }
  bool String(std::string* s, uint32_t limit) {
    uint32_t n = 0;
    if (!Get(&n) || n > limit || n > m_data.size() - m_at) return false;
    s->assign(m_data.data() + m_at, n);
    m_at += n;
    return true;
  }
  size_t At() const { return m_at; }
  size_t Left() const { return m_data.size() - m_at; }

 private:
  std::vector<char> m_data;
  size_t m_at = 0;
};

}  // namespace sphxr::app::state_format
