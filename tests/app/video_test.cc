// `urlab record --video CAM OUT`: a camera's frames written through ffmpeg, checked with ffprobe;
// a bad camera name or extension is a clear error.
#include <gtest/gtest.h>

#include <filesystem>

#include "mujoco_test.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

TEST(RecordVideo, WritesTheCameraToAnMp4) {
  const std::string dir = testing::MakeTempDir("video");
  const std::string out = dir + "/wrist.mp4";
  std::string log;
  ASSERT_EQ(testing::RunCommand(testing::UrlabBinary() + " record " +
                                    testing::TestData("cameras/two_cameras.yaml") +
                                    " --no-network --duration 1 --video rig/wrist " + out,
                                &log),
            0)
      << log;
  EXPECT_NE(log.find("video: " + out + " frames="), std::string::npos) << log;
  std::string probe;
  ASSERT_EQ(testing::RunCommand("ffprobe -v error -count_frames -show_entries "
                                "stream=codec_name,width,height,nb_read_frames -of compact " +
                                    out,
                                &probe),
            0)
      << probe;
  EXPECT_NE(probe.find("codec_name=h264|width=64|height=48"), std::string::npos) << probe;
  EXPECT_EQ(probe.find("nb_read_frames=0"), std::string::npos) << probe;
  fs::remove_all(dir);
}

TEST(RecordVideo, BadCameraOrExtensionIsAClearError) {
  const std::string dir = testing::MakeTempDir("video_bad");
  std::string log;
  EXPECT_NE(testing::RunCommand(testing::UrlabBinary() + " record " +
                                    testing::TestData("cameras/two_cameras.yaml") +
                                    " --no-network --duration 1 --video rig/nose " + dir + "/a.mp4",
                                &log),
            0);
  EXPECT_NE(log.find("no camera 'nose'"), std::string::npos) << log;
  EXPECT_NE(testing::RunCommand(testing::UrlabBinary() + " record " +
                                    testing::TestData("cameras/two_cameras.yaml") +
                                    " --no-network --duration 1 --video rig/top " + dir + "/a.avi",
                                &log),
            0);
  EXPECT_NE(log.find(".mp4 (H.264) or .webm"), std::string::npos) << log;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace urlab
