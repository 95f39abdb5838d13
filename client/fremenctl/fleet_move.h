// `fremenctl fleet move --map M --from A --to B` and `fremenctl fleet rebalance --daemons A,B,C,D`:
// maps moved between daemons while their writers keep sending (docs/fleet.md, "Moving a map").
//
// A move, for each map, in phases that every map passes together (--parallel maps at a time):
// 1. snapshots: ExportMap ONLINE_SNAPSHOT on the source streamed into ImportMap on the target; the
//    source goes on taking writes and records them (COPYING), the target's copy waits (INCOMING);
// 2. tails: the source stops the map's writes (SetMapMove STOP_WRITES: writers get UNAVAILABLE and
//    resend later; queries go on), then ExportMap TAIL — the batches logged since the snapshot —
//    is streamed into ImportMap on the target, which applies them and serves;
// 3. commit: once every tail is applied, each source marks its map MOVED (kept on disk: it never
//    takes writes again). A copy that fails before this gives the whole run up: the copies made are
//    deleted from their targets and the sources take writes again;
// 4. proxy: --proxy-command is run (e.g. render deploy/nginx's configuration for the new daemon
//    list and `nginx -s reload`), then with --proxy each moved map is asked for through the proxy
//    until the target answers (its copy serves, the source's says MOVED);
// 5. drop: each source deletes its copy.
// Without --proxy-command the run stops after 3 and says how to reconfigure the proxy; run it again
// with --proxy-reloaded once that is done. A run interrupted anywhere is repaired by running it
// again: a target's copy of a map whose source is not MOVED is stale and replaced; a MOVED source
// goes straight to 4 and 5.
#pragma once

#include "CLI/CLI.hpp"

namespace fremen::client {

// Adds `move` and `rebalance` to the `fleet` subcommand.
void RegisterFleetMoveCommands(CLI::App& fleet);

}  // namespace fremen::client
