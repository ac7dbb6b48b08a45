// Input files (common/src/text_file.cpp): what is not a regular file is refused instead of read (a FIFO
// would block the program), by every loader that reads through it (scenes, trajectories).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <string>

#include "refusal.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/interaction/trajectory.h"
#include "support.h"

namespace sphxr {
namespace {

using test::ExpectBriefRefusal;

TEST(TextFile, AFifoIsRefusedAsAnInputInsteadOfBlocking) {
  test::TempDir dir("text_file_fifo");
  const std::string fifo = dir.File("scene.fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  app::SceneFile scene;
  ExpectBriefRefusal(app::LoadScene(fifo, &scene), "not a regular file");
  interaction::Trajectory t;
  ExpectBriefRefusal(interaction::Trajectory::Load(fifo, &t), "not a regular file");
}

}  // namespace
}  // namespace sphxr
