#include "storage/data_dir_format.h"

#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"

namespace fremen::storage {

namespace {

constexpr absl::string_view kPrefix = "fremen data directory format ";

std::string FormatPath(const std::string& data_dir) { return data_dir + "/FORMAT"; }

}  // namespace

absl::StatusOr<int> ReadDataDirFormat(Env* env, const std::string& data_dir) {
  auto text = env->ReadFile(FormatPath(data_dir));
  if (absl::IsNotFound(text.status())) return 0;
  if (!text.ok()) return text.status();
  absl::string_view line = absl::StripTrailingAsciiWhitespace(*text);
  int format = 0;
  if (!absl::ConsumePrefix(&line, kPrefix) || !absl::SimpleAtoi(line, &format) || format <= 0) {
    return absl::DataLossError(absl::StrCat(FormatPath(data_dir), " does not say \"", kPrefix, "N\": \"",
                                            absl::CHexEscape(absl::StripTrailingAsciiWhitespace(*text)), "\""));
  }
  return format;
}

absl::Status WriteDataDirFormat(Env* env, const std::string& data_dir) {
  return WriteFileAtomically(env, FormatPath(data_dir), absl::StrCat(kPrefix, kDataDirFormat, "\n"));
}

absl::Status UnreadableFormatError(const std::string& data_dir, int format) {
  return absl::FailedPreconditionError(absl::StrCat(
      data_dir, " is data directory format ", format, ", written by a newer fremend; this one reads formats ",
      kOldestReadableDataDirFormat, " to ", kDataDirFormat, ". Its maps were left as they are: serve it with the fremend that wrote it."));
}

}  // namespace fremen::storage
