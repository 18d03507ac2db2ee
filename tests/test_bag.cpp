// The structural check that runs before Debian's rosbag_storage opens a bag: well-formed
// bags pass, damaged ones (cut, lengths changed, fuzz findings) are one InputError.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "io/bag_dataset.h"
#include "io/bag_structure.h"
#include "io/bag_writer.h"
#include "io/euroc_dataset.h"

namespace idyvins::io {
namespace {

std::optional<std::string> problemOf(const std::string& bytes) {
  std::istringstream in(bytes);
  return bagStructureProblem(in, bytes.size());
}

/// A small real bag: the first frames of the shared EuRoC excerpt, written like `simulate --format bag`.
std::string smallBag(const std::string& compression) {
  EurocDataset ds = readEurocDataset(IDYVINS_SHARED_DATA "/euroc_v101_micro");
  ds.cam0.resize(4), ds.cam1.resize(4);
  ds.pairs.erase(
      std::remove_if(ds.pairs.begin(), ds.pairs.end(), [](const StereoPair& p) { return p.i0 >= 4 || p.i1 >= 4; }),
      ds.pairs.end());
  // per process: another build's tests may write the same name at the same time
  const std::string path =
      ::testing::TempDir() + "/idyvins_small_" + std::to_string(::getpid()) + "_" + compression + ".bag";
  BagWriteOptions options;
  options.compression = compression;
  writeViodeBag(ds, path, options);
  std::ifstream in(path, std::ios::binary);
  std::string bytes(std::istreambuf_iterator<char>(in), {});
  std::filesystem::remove(path);
  return bytes;
}

TEST(BagStructure, WrittenBagsAreWellFormed) {
  for (const char* compression : {"none", "lz4", "bz2"}) {
    SCOPED_TRACE(compression);
    const std::string bag = smallBag(compression);
    ASSERT_GT(bag.size(), 4096u);
    const auto problem = problemOf(bag);
    EXPECT_FALSE(problem) << *problem;
  }
}

TEST(BagStructure, EveryCutIsFound) {
  const std::string bag = smallBag("none");
  for (std::size_t n : {std::size_t{0}, std::size_t{12}, std::size_t{20}, std::size_t{4000}, bag.size() / 3,
                        bag.size() / 2, bag.size() - 200, bag.size() - 1}) {
    SCOPED_TRACE(n);
    EXPECT_TRUE(problemOf(bag.substr(0, n)));
  }
}

TEST(BagStructure, LengthsPointingOutsideTheirRecordAreFound) {
  const std::string bag = smallBag("none");
  std::uint32_t header_len;
  std::memcpy(&header_len, bag.data() + 13, 4);
  {  // the bag header's first field claims more than its header holds
    std::string b = bag;
    const std::uint32_t huge = header_len + 100;
    std::memcpy(b.data() + 17, &huge, 4);
    const auto p = problemOf(b);
    ASSERT_TRUE(p);
    EXPECT_NE(p->find("byte 17: record header: field of"), std::string::npos) << *p;
  }
  {  // the first chunk's data length beyond the file
    std::string b = bag;
    std::uint32_t chunk_header_len, data_len;
    std::memcpy(&data_len, bag.data() + 13 + 4 + header_len, 4);
    const std::size_t first = 13 + 8 + header_len + data_len;
    std::memcpy(&chunk_header_len, bag.data() + first, 4);
    const std::uint32_t huge = 0x7fffffff;
    std::memcpy(b.data() + first + 4 + chunk_header_len, &huge, 4);
    EXPECT_TRUE(problemOf(b));
  }
}

TEST(BagStructure, FuzzFindingsAreRefusedWithOneClearError) {
  // Bags libFuzzer found (scripts/fuzz.sh) overflowing rosbag_storage's buffers: InputError, nothing else.
  int replayed = 0;
  for (const auto& e : std::filesystem::directory_iterator(IDYVINS_SOURCE_DIR "/tests/fuzz/regressions")) {
    if (e.path().filename().string().rfind("bag_", 0) != 0) continue;
    SCOPED_TRACE(e.path().string());
    try {
      indexBag(e.path().string(), BagTopics{});
      ADD_FAILURE() << "accepted";
    } catch (const InputError& err) {
      // the structural check speaks (byte offset), before rosbag_storage reads anything
      EXPECT_NE(std::string(err.what()).find("not a readable ROS1 bag (truncated or damaged?): byte "),
                std::string::npos)
          << err.what();
    }
    ++replayed;
  }
  EXPECT_GE(replayed, 1);
}

}  // namespace
}  // namespace idyvins::io
