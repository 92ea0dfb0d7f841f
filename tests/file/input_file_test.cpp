// file/input_file.hpp: a regular file is read whole and byte for byte, whatever its size relative to the read
// buffers (the size fstat gives, then a 4 KiB probe for more); what is not a regular file, or is empty, is refused
// before anything is read; every file checked is remembered as an input of the job; a file held open is read in
// parts.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <string>

#include "file/input_file.hpp"
#include "qdmr/core/error.hpp"
#include "support/test_support.hpp"

namespace qdmr::test {
namespace {

namespace fs = std::filesystem;

std::string pattern(std::size_t size) {
  std::string bytes(size, '\0');
  for (std::size_t i = 0; i < size; ++i) bytes[i] = char((i * 131 + i / 251) & 0xff);
  return bytes;
}

std::string error_of(const fs::path& file) {
  try {
    read_input_file(file, "test", InputKind::Obj);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(InputFile, ReadsEveryByteAtTheSizesAroundItsBuffers) {
  TempDir dir;
  // 4096: the probe's size; 65536 and its neighbours: the growth step the reader used before the probe.
  for (const std::size_t size : {1u, 2u, 4095u, 4096u, 4097u, 8192u, 65535u, 65536u, 65537u, 300001u}) {
    const fs::path file = dir.path() / (std::to_string(size) + ".obj");
    const std::string bytes = pattern(size);
    write_file(file, bytes);
    const std::string read = read_input_file(file, "test", InputKind::Obj);
    ASSERT_EQ(read.size(), size);
    EXPECT_TRUE(read == bytes) << "size " << size;
  }
}

TEST(InputFile, RefusesEmptyFilesFifosAndDirectoriesByName) {
  TempDir dir;
  const fs::path empty = dir.path() / "empty.obj";
  write_file(empty, "");
  EXPECT_NE(error_of(empty).find("is empty (0 bytes)"), std::string::npos) << error_of(empty);
  const fs::path fifo = dir.path() / "pipe.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(error_of(fifo).find("is a FIFO"), std::string::npos) << error_of(fifo);
  EXPECT_NE(error_of(dir.path()).find("is a directory"), std::string::npos) << error_of(dir.path());
  EXPECT_NE(error_of(dir.path() / "missing.obj").find("file not found"), std::string::npos);
}

TEST(InputFile, ReadsPartsAndNamesAFileThatShrank) {
  TempDir dir;
  const fs::path file = dir.path() / "model.glb";
  const std::string bytes = pattern(100000);
  write_file(file, bytes);
  const InputFile open(file, "test", InputKind::Gltf);
  EXPECT_EQ(open.size(), bytes.size());
  EXPECT_EQ(open.read(70000, 30000), bytes.substr(70000));
  EXPECT_EQ(open.read(3, 5), bytes.substr(3, 5));
  // The file loses its end after it was opened: the missing bytes are an error, not zeros.
  ASSERT_EQ(::truncate(file.c_str(), 50000), 0);
  try {
    open.read(40000, 20000);
    ADD_FAILURE() << "read past the end";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("ended at byte 50000"), std::string::npos) << e.what();
  }
  write_file(dir.path() / "empty.glb", "");
  EXPECT_THROW(InputFile(dir.path() / "empty.glb", "test", InputKind::Gltf), Error);
}

TEST(InputFile, RemembersWhatItReadAsAnInputOfTheJob) {
  TempDir dir;
  const fs::path file = dir.path() / "model.obj";
  write_file(file, "v 0 0 0\n");
  read_input_file(file, "test", InputKind::Obj);
  const std::vector<KnownInput> known = known_inputs();
  struct stat st {};
  ASSERT_EQ(::stat(file.c_str(), &st), 0);
  const FileIdentity id{st.st_dev, st.st_ino};
  EXPECT_TRUE(std::any_of(known.begin(), known.end(), [&](const KnownInput& k) { return k.id == id; }));
}

}  // namespace
}  // namespace qdmr::test
