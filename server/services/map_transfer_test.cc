#include "server/services/map_transfer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <xxhash.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "storage/testing/scans.h"
#include "testing/temp_dir.h"

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

// A stream of a two-shard map whose files are `a` and `b`, cut into chunks of `chunk` bytes.
std::vector<v1::MapChunk> Stream(const std::string& a, const std::string& b, size_t chunk) {
  std::vector<v1::MapChunk> messages(1);
  v1::MapExportHeader& header = *messages[0].mutable_header();
  header.set_format(kMapExportFormat);
  header.set_map("m");
  header.set_map_info(storage::EncodeMapInfo(storage::testing::GridMap("m", 4, 4, 1, 2)));
  uint64_t chunks = 0, bytes = 0;
  const std::string files[2] = {a, b};
  for (uint32_t f = 0; f < 2; ++f) {
    v1::MapExportFile& file = *header.add_files();
    file.set_path(absl::StrCat("shard-", f, "/data.mdb"));
    file.set_bytes(files[f].size());
    file.set_xxh3(XXH3_64bits(files[f].data(), files[f].size()));
  }
  for (uint32_t f = 0; f < 2; ++f) {
    for (size_t offset = 0; offset < files[f].size(); offset += chunk) {
      v1::MapFileChunk& data = *messages.emplace_back().mutable_data();
      data.set_file(f);
      data.set_offset(offset);
      data.set_data(files[f].substr(offset, chunk));
      data.set_xxh3(XXH3_64bits(data.data().data(), data.data().size()));
      ++chunks;
      bytes += data.data().size();
    }
  }
  messages.emplace_back().mutable_trailer()->set_chunks(chunks);
  messages.back().mutable_trailer()->set_bytes(bytes);
  return messages;
}

// The first error of adding `messages`, else Finish's status.
absl::Status Receive(const std::string& dir, const std::vector<v1::MapChunk>& messages) {
  MapImportWriter writer(dir);
  for (const v1::MapChunk& m : messages) {
    if (absl::Status added = writer.Add(m); !added.ok()) return added;
  }
  return writer.Finish();
}

std::string Read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

TEST(MapImportWriterTest, WritesEachFileAsSentAndChecksTheTrailer) {
  fremen::testing::TempDir dir;
  const std::string a = "the first shard's bytes", b = "and the second's, a little longer";
  ASSERT_TRUE(Receive(dir.path(), Stream(a, b, 5)).ok());
  EXPECT_EQ(Read(dir.path() + "/shard-0/data.mdb"), a);
  EXPECT_EQ(Read(dir.path() + "/shard-1/data.mdb"), b);
  EXPECT_TRUE(std::filesystem::exists(dir.path() + "/map.info"));
}

TEST(MapImportWriterTest, DamagedMisplacedOrMissingChunksAreDataLoss) {
  const std::vector<v1::MapChunk> good = Stream("0123456789abcdef", "fedcba9876543210", 4);
  const auto expect_loss = [](const std::vector<v1::MapChunk>& messages, const std::string& says) {
    fremen::testing::TempDir dir;
    const absl::Status status = Receive(dir.path(), messages);
    EXPECT_TRUE(absl::IsDataLoss(status)) << status;
    EXPECT_THAT(status.message(), HasSubstr(says));
  };
  std::vector<v1::MapChunk> flipped = good;
  (*flipped[3].mutable_data()->mutable_data())[1] ^= 1;
  expect_loss(flipped, "checksum mismatch");
  std::vector<v1::MapChunk> repeated = good;
  repeated.insert(repeated.begin() + 2, good[2]);
  expect_loss(repeated, "a chunk is missing or repeated");
  std::vector<v1::MapChunk> skipped = good;
  skipped.erase(skipped.begin() + 4);  // the first file's last chunk
  expect_loss(skipped, "ends at byte 12 of 16");
  std::vector<v1::MapChunk> torn(good.begin(), good.end() - 1);
  expect_loss(torn, "before its trailer");
  expect_loss(std::vector<v1::MapChunk>(good.begin() + 1, good.end()), "does not start with a header");
  std::vector<v1::MapChunk> miscounted = good;
  miscounted.back().mutable_trailer()->set_chunks(7);
  expect_loss(miscounted, "the trailer counts 7 chunks");
  std::vector<v1::MapChunk> longer = good;
  longer[1].mutable_data()->set_data("0123456789abcdefXX");
  longer[1].mutable_data()->set_xxh3(XXH3_64bits("0123456789abcdefXX", 18));
  expect_loss(longer, "goes past the 16 bytes");
  std::vector<v1::MapChunk> whole = good;  // chunks intact, the file not what the header says
  whole[0].mutable_header()->mutable_files(1)->set_xxh3(1);
  expect_loss(whole, "shard-1/data.mdb: checksum mismatch");
  std::vector<v1::MapChunk> after = good;
  after.push_back(good[1]);
  expect_loss(after, "a message follows the trailer");
}

TEST(MapImportWriterTest, AHeaderOfAnotherFormatOrOtherFilesIsRefused) {
  fremen::testing::TempDir dir;
  std::vector<v1::MapChunk> later = Stream("a", "b", 4);
  later[0].mutable_header()->set_format(kMapExportFormat + 1);
  EXPECT_TRUE(absl::IsFailedPrecondition(Receive(dir.path(), later)));
  std::vector<v1::MapChunk> escaping = Stream("a", "b", 4);
  escaping[0].mutable_header()->mutable_files(1)->set_path("../../etc/passwd");
  const absl::Status bad_path = Receive(dir.path(), escaping);
  EXPECT_TRUE(absl::IsInvalidArgument(bad_path)) << bad_path;
  EXPECT_THAT(bad_path.message(), HasSubstr("header.files[1].path must be \"shard-1/data.mdb\""));
  std::vector<v1::MapChunk> garbled = Stream("a", "b", 4);
  garbled[0].mutable_header()->set_map_info("not a map");
  EXPECT_TRUE(absl::IsDataLoss(Receive(dir.path(), garbled)));
}

}  // namespace
}  // namespace fremen::server
