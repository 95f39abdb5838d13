// The exit codes of fremenctl, shared by main() and the subcommands, so that scripts can tell a
// mistake in the command line from a failure of the command.
#pragma once

namespace fremen::client {

inline constexpr int kExitOk = 0;
// The command failed: unreadable or invalid input, and later an unreachable daemon or an RPC error.
inline constexpr int kExitFailure = 1;
// The command line is wrong: unknown option, missing or out-of-range value.
inline constexpr int kExitUsage = 2;

}  // namespace fremen::client
