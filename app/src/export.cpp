#include "sphxr/app/export.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <cstring>
#include <memory>
#include <type_traits>

namespace sphxr::app {
namespace {

struct FileCloser {
  void operator()(FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<FILE, FileCloser>;

// Closes `f` and reports any write that failed, including the last buffered bytes that only fclose
// writes (a full disk). The FileCloser above is for early returns, whose error is already reported.
Status Close(File* f, const std::string& path) {
  FILE* raw = f->release();
  const bool failed = std::ferror(raw) != 0;
  if (std::fclose(raw) != 0 || failed) {
    // A truncated export would look like a real one: removed (a regular file only, never a device).
    std::error_code ignored;
    if (std::filesystem::is_regular_file(path, ignored)) std::filesystem::remove(path, ignored);
    return Status::Error(path + ": write failed (disk full?); no partial file is left");
  }
  return Status::Ok();
}

// Components of one field as floats/ints: Vec4 fields export x, y, z (w is a spare lane).
template <class T>
constexpr int Components() {
  if constexpr (std::is_same_v<T, sim::Vec4>) return 3;
  else return 1;
}
template <class T>
const char* PlyType() {
  if constexpr (std::is_same_v<T, sim::Vec4> || std::is_same_v<T, float>) return "float";
  else if constexpr (std::is_same_v<T, uint32_t>) return "uint";
  else return "int";
}
template <class T>
const char* VtkType() {
  if constexpr (std::is_same_v<T, sim::Vec4> || std::is_same_v<T, float>) return "float";
  else if constexpr (std::is_same_v<T, uint32_t>) return "unsigned_int";
  else return "int";
}

uint32_t ToBigEndian(uint32_t v) { return __builtin_bswap32(v); }

template <class T>
void PutBigEndian(FILE* f, const T& value) {
  if constexpr (std::is_same_v<T, sim::Vec4>) {
    const float c[3] = {value.x, value.y, value.z};
    for (float x : c) {
      uint32_t u;
      std::memcpy(&u, &x, 4);
      u = ToBigEndian(u);
      std::fwrite(&u, 4, 1, f);
    }
  } else if constexpr (sizeof(T) == 8) {  // the stamp's time (double)
    uint64_t u;
    std::memcpy(&u, &value, 8);
    u = __builtin_bswap64(u);
    std::fwrite(&u, 8, 1, f);
  } else {
    uint32_t u;
    static_assert(sizeof(T) == 4, "export supports 4-byte scalar fields");
    std::memcpy(&u, &value, 4);
    u = ToBigEndian(u);
    std::fwrite(&u, 4, 1, f);
  }
}

template <class T>
void PutLittleEndian(FILE* f, const T& value) {
  if constexpr (std::is_same_v<T, sim::Vec4>) {
    const float c[3] = {value.x, value.y, value.z};
    std::fwrite(c, 4, 3, f);
  } else {
    static_assert(sizeof(T) == 4, "export supports 4-byte scalar fields");
    std::fwrite(&value, 4, 1, f);
  }
}

Status OpenForWrite(const std::string& path, File* out) {
  out->reset(std::fopen(path.c_str(), "wb"));
  if (!*out) return Status::Error(path + ": cannot open for writing: " + std::strerror(errno));
  return Status::Ok();
}

void PlyStamp(std::FILE* f, const ExportStamp& stamp) {
  if (stamp.step >= 0) std::fprintf(f, "comment step %lld time %.17g\n", static_cast<long long>(stamp.step), stamp.time);
}

}  // namespace

Status WritePly(const std::string& path, const sim::HostFluid& fluid, const ExportStamp& stamp) {
  File f;
  if (Status s = OpenForWrite(path, &f); !s) return s;
  const size_t n = fluid.size();
  std::fprintf(f.get(), "ply\nformat binary_little_endian 1.0\ncomment sphxr fluid particles\n");
  PlyStamp(f.get(), stamp);
  std::fprintf(f.get(), "element vertex %zu\n", n);
  // position first, named x y z so that every reader finds the points.
#define SPHXR_PLY_HEADER(type, name)                                                                  \
  if (std::strcmp(#name, "position") == 0) {                                                         \
    std::fprintf(f.get(), "property float x\nproperty float y\nproperty float z\n");                  \
  } else if (Components<type>() == 3) {                                                              \
    for (const char* c : {"x", "y", "z"}) std::fprintf(f.get(), "property float %s_%s\n", #name, c); \
  } else {                                                                                           \
    std::fprintf(f.get(), "property %s %s\n", PlyType<type>(), #name);                               \
  }
  SPHXR_FLUID_FIELDS(SPHXR_PLY_HEADER)
#undef SPHXR_PLY_HEADER
  std::fprintf(f.get(), "end_header\n");
  for (size_t i = 0; i < n; ++i) {
#define SPHXR_PLY_VALUE(type, name) PutLittleEndian(f.get(), fluid.name[i]);
    SPHXR_FLUID_FIELDS(SPHXR_PLY_VALUE)
#undef SPHXR_PLY_VALUE
  }
  return Close(&f, path);
}

Status WriteDiffusePly(const std::string& path, const sim::HostDiffuse& diffuse, const ExportStamp& stamp) {
  File f;
  if (Status s = OpenForWrite(path, &f); !s) return s;
  std::fprintf(f.get(), "ply\nformat binary_little_endian 1.0\ncomment sphxr diffuse particles (spray, foam, bubbles)\n");
  PlyStamp(f.get(), stamp);
  std::fprintf(f.get(), "element vertex %d\n", diffuse.count);
  std::fprintf(f.get(), "property float x\nproperty float y\nproperty float z\nproperty float lifetime\n"
                        "property float velocity_x\nproperty float velocity_y\nproperty float velocity_z\n"
                        "property uchar kind\nend_header\n");
  for (int i = 0; i < diffuse.count; ++i) {
    const sim::Vec4& p = diffuse.position[i];
    const sim::Vec4& v = diffuse.velocity[i];
    const float values[7] = {p.x, p.y, p.z, p.w, v.x, v.y, v.z};
    std::fwrite(values, 4, 7, f.get());
    const uint8_t kind = static_cast<uint8_t>(sim::DiffuseKindOf(v));
    std::fwrite(&kind, 1, 1, f.get());
  }
  return Close(&f, path);
}

Status WriteVtk(const std::string& path, const sim::HostFluid& fluid, const ExportStamp& stamp) {
  File f;
  if (Status s = OpenForWrite(path, &f); !s) return s;
  const size_t n = fluid.size();
  std::fprintf(f.get(), "# vtk DataFile Version 3.0\nsphxr fluid particles\nBINARY\nDATASET POLYDATA\n");
  if (stamp.step >= 0) {
    std::fprintf(f.get(), "FIELD FieldData 2\nTIME 1 1 double\n");
    PutBigEndian(f.get(), stamp.time);
    std::fprintf(f.get(), "\nCYCLE 1 1 int\n");
    PutBigEndian(f.get(), static_cast<int32_t>(std::min<int64_t>(stamp.step, INT32_MAX)));
    std::fprintf(f.get(), "\n");
  }
  std::fprintf(f.get(), "POINTS %zu float\n", n);
  for (size_t i = 0; i < n; ++i) PutBigEndian(f.get(), fluid.position[i]);
  std::fprintf(f.get(), "\nVERTICES %zu %zu\n", n, 2 * n);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t cell[2] = {ToBigEndian(1u), ToBigEndian(static_cast<uint32_t>(i))};
    std::fwrite(cell, 4, 2, f.get());
  }
  std::fprintf(f.get(), "\nPOINT_DATA %zu\n", n);
#define SPHXR_VTK_FIELD(type, name)                                                                    \
  if (std::strcmp(#name, "position") != 0) {                                                          \
    if (Components<type>() == 3) std::fprintf(f.get(), "VECTORS %s float\n", #name);                  \
    else std::fprintf(f.get(), "SCALARS %s %s 1\nLOOKUP_TABLE default\n", #name, VtkType<type>());   \
    for (size_t i = 0; i < n; ++i) PutBigEndian(f.get(), fluid.name[i]);                              \
    std::fprintf(f.get(), "\n");                                                                      \
  }
  SPHXR_FLUID_FIELDS(SPHXR_VTK_FIELD)
#undef SPHXR_VTK_FIELD
  return Close(&f, path);
}

Status WriteSurfacePly(const std::string& path, const sim::SurfaceMesh& mesh, const ExportStamp& stamp) {
  File f;
  if (Status s = OpenForWrite(path, &f); !s) return s;
  const int64_t n = mesh.VertexCount();
  std::fprintf(f.get(),
               "ply\nformat binary_little_endian 1.0\ncomment sphxr water surface (triangle soup)\n");
  PlyStamp(f.get(), stamp);
  std::fprintf(f.get(),
               "element vertex %lld\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
               "property float nz\nelement face %lld\nproperty list uchar uint vertex_indices\nend_header\n",
               static_cast<long long>(n), static_cast<long long>(n / 3));
  for (int64_t v = 0; v < n; ++v) {
    std::fwrite(&mesh.positions[static_cast<size_t>(3 * v)], 4, 3, f.get());
    std::fwrite(&mesh.normals[static_cast<size_t>(3 * v)], 4, 3, f.get());
  }
  for (int64_t t = 0; t < n / 3; ++t) {
    const unsigned char three = 3;
    const uint32_t index[3] = {static_cast<uint32_t>(3 * t), static_cast<uint32_t>(3 * t + 1),
                               static_cast<uint32_t>(3 * t + 2)};
    std::fwrite(&three, 1, 1, f.get());
    std::fwrite(index, 4, 3, f.get());
  }
  return Close(&f, path);
}

Status WriteSurfaceObj(const std::string& path, const sim::SurfaceMesh& mesh, const ExportStamp& stamp) {
  File f;
  if (Status s = OpenForWrite(path, &f); !s) return s;
  const int64_t n = mesh.VertexCount();
  std::fprintf(f.get(), "# sphxr water surface: %lld triangles\n", static_cast<long long>(n / 3));
  if (stamp.step >= 0) std::fprintf(f.get(), "# step %lld time %.17g\n", static_cast<long long>(stamp.step), stamp.time);
  for (int64_t v = 0; v < n; ++v) {
    const float* p = &mesh.positions[static_cast<size_t>(3 * v)];
    std::fprintf(f.get(), "v %.7g %.7g %.7g\n", p[0], p[1], p[2]);
  }
  for (int64_t v = 0; v < n; ++v) {
    const float* q = &mesh.normals[static_cast<size_t>(3 * v)];
    std::fprintf(f.get(), "vn %.6g %.6g %.6g\n", q[0], q[1], q[2]);
  }
  for (int64_t t = 0; t < n / 3; ++t) {
    const long long a = 3 * t + 1, b = a + 1, c = a + 2;  // OBJ counts from 1
    std::fprintf(f.get(), "f %lld//%lld %lld//%lld %lld//%lld\n", a, a, b, b, c, c);
  }
  return Close(&f, path);
}

}  // namespace sphxr::app
