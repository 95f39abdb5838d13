#include "client/fremenctl/transfer_commands.h"

#include <google/protobuf/io/zero_copy_stream_impl.h>
#include <google/protobuf/util/delimited_message_util.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/print.h"

namespace fremen::client {

namespace {

// The first line of an export file.
constexpr char kMagic[] = "fremen map export 1\n";

// Copies of whole maps: the global --timeout (meant for queries) is raised to at least this.
constexpr double kMinTransferSeconds = 3600;

}  // namespace

CallOptions TransferCall() { return GlobalCallOfAtLeast(absl::Seconds(kMinTransferSeconds)); }

void RegisterExportCommand(CLI::App& app) {
  struct Args {
    std::string map, out;
  };
  auto a = std::make_shared<Args>();
  CLI::App* command = app.add_subcommand(
      "export", "A consistent copy of a map into a local file (for `fremenctl import` on any daemon)");
  command->add_option("--map", a->map, "the map")->required();
  command->add_option("--out", a->out, "the file to write (replaced once complete)")->required();
  command->callback([a] {
    Client client = ConnectOrExit("export");
    const std::string partial = a->out + ".partial";
    uint64_t bytes = 0;
    absl::Status status;
    {
      std::ofstream file(partial, std::ios::binary | std::ios::trunc);
      if (!file) FailCall("export", a->out, absl::FailedPreconditionError(absl::StrCat("cannot write ", partial)));
      file << kMagic;
      google::protobuf::io::OstreamOutputStream out(&file);
      status = client.ExportMap(
          a->map,
          [&](const v1::MapChunk& chunk) {
            bytes += chunk.data().data().size();
            if (!google::protobuf::util::SerializeDelimitedToZeroCopyStream(chunk, &out)) {
              return absl::InternalError(absl::StrCat("cannot write ", partial));
            }
            return absl::OkStatus();
          },
          TransferCall());
    }
    std::error_code error;
    if (!status.ok()) {
      std::filesystem::remove(partial, error);
      FailCall("export", absl::StrCat("map ", a->map), status, a->map);
    }
    std::filesystem::rename(partial, a->out, error);
    if (error) FailCall("export", a->out, absl::InternalError(error.message()));
    std::printf("exported map %s to %s (%s of data)\n", a->map.c_str(), a->out.c_str(), FormatBytes(bytes).c_str());
  });
}

void RegisterImportCommand(CLI::App& app) {
  struct Args {
    std::string in, map;
  };
  auto a = std::make_shared<Args>();
  CLI::App* command = app.add_subcommand("import", "A file written by `fremenctl export` as a new map");
  command->add_option("--in", a->in, "the file")->required();
  command->add_option("--map", a->map, "the new map's name (default: the exported map's)");
  command->callback([a] {
    std::ifstream file(a->in, std::ios::binary);
    if (!file) FailCall("import", a->in, absl::NotFoundError(absl::StrCat("cannot read ", a->in)));
    std::string magic(sizeof(kMagic) - 1, '\0');
    file.read(magic.data(), static_cast<std::streamsize>(magic.size()));
    if (!file || magic != kMagic) {
      FailCall("import", a->in,
               absl::InvalidArgumentError(absl::StrCat(a->in, " is not a file written by `fremenctl export`")));
    }
    google::protobuf::io::IstreamInputStream in(&file);
    // The map's name is in the header, the file's first message: read it before connecting, so
    // that the call carries x-fremen-map and a proxy routes it to the map's owner.
    v1::MapChunk header;
    bool clean_eof = false;
    if (!google::protobuf::util::ParseDelimitedFromZeroCopyStream(&header, &in, &clean_eof) || !header.has_header()) {
      FailCall("import", a->in, absl::DataLossError(absl::StrCat(a->in, ": no header (the file is damaged)")));
    }
    const std::string name = a->map.empty() ? header.header().map() : a->map;
    header.mutable_header()->set_map(name);
    bool sent_header = false, trailer = false;
    Client client = ConnectOrExit("import");
    auto imported = client.ImportMap(
        name,
        [&](v1::MapChunk& chunk) -> absl::StatusOr<bool> {
          if (!sent_header) {
            sent_header = true;
            chunk = header;
            return true;
          }
          if (trailer) return false;
          bool eof = false;
          if (!google::protobuf::util::ParseDelimitedFromZeroCopyStream(&chunk, &in, &eof)) {
            // A file cut short ends the stream: the daemon refuses it (DATA_LOSS) for want of a trailer.
            if (eof) return false;
            return absl::DataLossError(absl::StrCat(a->in, ": a damaged message (the file is damaged)"));
          }
          trailer = chunk.has_trailer();
          return true;
        },
        TransferCall());
    if (!imported.ok()) {
      absl::Status status = imported.status();
      if (absl::IsAlreadyExists(status)) {
        status = absl::AlreadyExistsError(absl::StrCat(status.message(), "; import under another name with --map NAME"));
      }
      FailCall("import", absl::StrCat("map ", name), status);
    }
    std::printf("imported map %s from %s (%s in %.2f s)\n", imported->map().name().c_str(), a->in.c_str(),
                FormatBytes(imported->bytes()).c_str(), imported->duration_seconds());
  });
}

}  // namespace fremen::client
