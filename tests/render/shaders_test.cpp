// Every shader program of the renderer compiled offline by Khronos' reference compiler
// (glslangValidator, Debian's glslang-tools), so a GLSL error fails here, before any driver sees it,
// and a construct one driver accepts but the language does not (llvmpipe is lenient) is caught too.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "shaders.h"  // render/src: the programs' sources
#include "support.h"

namespace sphxr::test {
namespace {

std::string Concatenate(const std::vector<const char*>& parts) {
  std::string text;
  for (const char* p : parts) text += p;
  return text;
}

struct Compiled {
  int code = -1;
  std::string output;
};

Compiled Validate(const std::string& path) {
  const std::string log = path + ".log";
  const std::string command = std::string("'") + SPHXR_GLSLANG_VALIDATOR + "' '" + path + "' >'" + log + "' 2>&1";
  const int status = std::system(command.c_str());
  Compiled c;
  c.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  c.output = ReadFile(log);
  return c;
}

TEST(ShadersTest, EveryProgramCompilesWithTheReferenceCompiler) {
  ASSERT_TRUE(std::filesystem::exists(SPHXR_GLSLANG_VALIDATOR))
      << SPHXR_GLSLANG_VALIDATOR << " is missing: install glslang-tools (scripts/setup.sh does)";
  TempDir dir("shaders");
  int checked = 0;
  for (const render::shaders::ProgramSource& program : render::shaders::Programs()) {
    std::string stem = program.name;
    for (char& c : stem) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    for (const auto& [suffix, parts] : {std::pair<const char*, const std::vector<const char*>*>{".vert", &program.vertex},
                                        std::pair<const char*, const std::vector<const char*>*>{".frag", &program.fragment}}) {
      const std::string path = dir.File(stem + suffix);
      std::ofstream(path) << Concatenate(*parts);
      const Compiled c = Validate(path);
      EXPECT_EQ(c.code, 0) << program.name << suffix << ":\n" << c.output;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2 * static_cast<int>(render::shaders::Programs().size()));
}

TEST(ShadersTest, TheReferenceCompilerRejectsABrokenShader) {
  // The check above can fail: a fragment shader with a type error is refused.
  TempDir dir("shaders_broken");
  const std::string path = dir.File("broken.frag");
  std::ofstream(path) << render::shaders::kCommon << "void main() { vec3 c = SkyColor(1.0); }\n";
  EXPECT_NE(Validate(path).code, 0);
}

}  // namespace
}  // namespace sphxr::test
