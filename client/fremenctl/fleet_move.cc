#include "client/fremenctl/fleet_move.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <functional>
#include <thread>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"
#include "base/mutex.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"
#include "client/fremenctl/fleet_maps.h"
#include "client/fremenctl/transfer_commands.h"
#include "client/lib/fleet_addresses.h"
#include "client/lib/placement.h"

namespace fremen::client {

namespace {

struct MoveArgs {
  std::string daemons;  // rebalance: the fleet after the change
  std::string map, from, to;  // move
  std::string proxy_command;
  std::string proxy;
  bool proxy_reloaded = false;
  // After the proxy routes to the new owners, how long the old copies stay: a proxy's connections
  // opened before its reload keep the old configuration until it closes them (nginx's old workers
  // send GOAWAY and finish their streams), and a call on one still reaches the old copy.
  double drain_seconds = 5;
  bool dry_run = false;
  // Maps copied at once (rebalance).
  int parallel = 4;
  // Test only: once every snapshot is copied (writes still going on), create this file and wait
  // until it is removed, so that a test acts at that point without guessing when it is.
  std::string pause_after_snapshot;
};

// One map to move, and what an earlier run left of it.
struct Move {
  std::string map, from, to;
  bool committed = false;  // the source's copy is MOVED already
  bool stale_target = false;  // the target holds a copy from a run that did not commit
  bool source_stopped = false;  // the source's writes were left stopped by a run that did not commit
  uint64_t snapshot_lsn = 0;    // the copy's snapshot (phase 1), which its tail follows
  bool copied = false;          // the snapshot is on the target (so undone if the run gives up)
};

// Runs job(i) for i in [0, n), `parallel` at a time; their statuses, by i.
std::vector<absl::Status> RunParallel(size_t n, int parallel, const std::function<absl::Status(size_t)>& job) {
  std::vector<absl::Status> statuses(n);
  std::atomic<size_t> next{0};
  std::vector<std::thread> threads;
  const size_t count = std::min<size_t>(n, static_cast<size_t>(std::max(parallel, 1)));
  for (size_t t = 0; t < count; ++t) {
    threads.emplace_back([&] {
      for (size_t i; (i = next++) < n;) statuses[i] = job(i);
    });
  }
  for (std::thread& t : threads) t.join();
  return statuses;
}

// The daemons' clients, by address.
class Fleet {
 public:
  Fleet(const std::string& command, const std::vector<std::string>& addresses)
      : client_(ConnectFleetOrExit(command, addresses)) {}
  const Client& Of(const std::string& address) const {
    for (const FleetMember& d : client_.members()) {
      if (d.address == address) return d.client;
    }
    std::abort();  // every address was connected
  }
  const FleetClient& client() const { return client_; }

 private:
  FleetClient client_;
};

// The map's copy on one daemon, or nullopt when it holds none (or does not answer: an error).
absl::StatusOr<std::optional<v1::Map>> CopyOn(const Client& client, const std::string& map) {
  auto got = client.GetMap(map, GlobalCall());
  if (absl::IsNotFound(got.status())) return std::nullopt;
  if (!got.ok()) return got.status();
  return *std::move(got);
}

std::string RenderHint(const std::vector<std::string>& daemons) {
  std::string args;
  for (const std::string& d : daemons) absl::StrAppend(&args, " --daemon ", d);
  return absl::StrCat("deploy/nginx/render.py", args, " > nginx.conf && nginx -s reload");
}

class Mover {
 public:
  Mover(std::string command, const MoveArgs& args, const Fleet& fleet)
      : command_(std::move(command)), args_(args), fleet_(fleet) {}

  // Phases 1 to 4 (fleet_move.h) for `moves`; exits 1 when a phase fails.
  void Run(std::vector<Move> moves, const std::vector<std::string>& new_daemons) {
    if (moves.empty()) {
      std::printf("nothing to move: every map is held by its owner\n");
      return;
    }
    for (const Move& m : moves) {
      std::printf("%s %s -> %s%s\n", m.map.c_str(), m.from.c_str(), m.to.c_str(),
                  m.committed ? " (copied already: finishing)" : "");
    }
    if (args_.dry_run) return;
    Copy(moves);
    Commit(moves);
    if (!args_.proxy_command.empty()) {
      std::printf("reconfiguring the proxy: %s\n", args_.proxy_command.c_str());
      std::fflush(stdout);
      if (const int rc = std::system(args_.proxy_command.c_str()); rc != 0) {
        Fail(absl::StrCat("--proxy-command exited with ", rc,
                          "; the maps are on their new owners and their old copies refuse writes: fix the proxy, "
                          "then run this again"));
      }
    } else if (!args_.proxy_reloaded) {
      std::printf(
          "the maps are copied; their old copies refuse writes until the proxy routes by the new daemon list:\n"
          "  %s\nthen run this command again with --proxy-reloaded to delete the old copies\n",
          RenderHint(new_daemons).c_str());
      throw CLI::RuntimeError(kExitFailure);
    }
    if (!args_.proxy.empty()) AwaitProxy(moves);
    absl::SleepFor(absl::Seconds(args_.drain_seconds));
    Drop(moves);
    std::printf("moved %zu maps\n", moves.size());
  }

 private:
  [[noreturn]] void Fail(const std::string& message) const {
    std::fprintf(stderr, "fremenctl %s: %s\n", command_.c_str(), message.c_str());
    throw CLI::RuntimeError(kExitFailure);
  }

  // Phase 1, snapshots (writes go on), then phase 1b, tails (writes stopped): every map's
  // snapshot is copied before any map's writes stop, so that a map's writers wait only for the
  // tails and the proxy's reload, not for the other maps' snapshots.
  void Copy(std::vector<Move>& moves) {
    std::vector<Move*> todo;
    for (Move& m : moves) {
      if (!m.committed) todo.push_back(&m);
    }
    if (todo.empty()) return;
    ReportFailures(todo, RunParallel(todo.size(), args_.parallel, [&](size_t i) { return Snapshot(*todo[i]); }),
                   "copying the snapshot of map ");
    std::erase_if(todo, [](const Move* m) { return m->committed; });
    if (!args_.pause_after_snapshot.empty()) PauseForTest();
    ReportFailures(todo, RunParallel(todo.size(), args_.parallel, [&](size_t i) { return CopyTail(*todo[i]); }),
                   "copying the tail of map ");
  }

  absl::Status Snapshot(Move& m) {
    const Client& from = fleet_.Of(m.from);
    const Client& to = fleet_.Of(m.to);
    if (m.stale_target) {
      // Left by a run that did not commit: the source has been the map's owner since.
      absl::Status deleted = to.DeleteMap(m.map, GlobalCall());
      if (!deleted.ok() && !absl::IsNotFound(deleted)) return deleted;
    }
    if (m.source_stopped) {
      // An online snapshot starts only where writes go on.
      auto resumed = from.SetMapMove(m.map, v1::MAP_MOVE_STEP_RESUME_WRITES, "", GlobalCall());
      if (!resumed.ok()) return resumed.status();
    }
    const absl::Time start = absl::Now();
    auto copied = from.CopyMapTo(to, m.map, "", TransferCall(), v1::MAP_EXPORT_KIND_ONLINE_SNAPSHOT);
    if (!copied.ok()) {
      if (absl::IsFailedPrecondition(copied.status())) {
        // Committed by a run that this one's listing raced with?
        auto there = CopyOn(from, m.map);
        if (there.ok() && *there && (*there)->move_state() == v1::MAP_MOVE_STATE_MOVED) {
          m.committed = true;
          return absl::OkStatus();
        }
      }
      return copied.status();
    }
    m.copied = true;
    m.snapshot_lsn = copied->snapshot_lsn();
    Say(absl::StrFormat("copied the snapshot of %s to %s (%llu bytes in %.2f s; writes go on)", m.map, m.to,
                        static_cast<unsigned long long>(copied->bytes()), absl::ToDoubleSeconds(absl::Now() - start)));
    return absl::OkStatus();
  }

  absl::Status CopyTail(Move& m) {
    const Client& from = fleet_.Of(m.from);
    const absl::Time start = absl::Now();
    // Every batch submitted before this is applied when it returns: the tail is complete.
    auto stopped = from.SetMapMove(m.map, v1::MAP_MOVE_STEP_STOP_WRITES, "", GlobalCall());
    if (!stopped.ok()) return stopped.status();
    auto tail = from.CopyMapTo(fleet_.Of(m.to), m.map, "", TransferCall(), v1::MAP_EXPORT_KIND_TAIL, m.snapshot_lsn);
    if (!tail.ok()) return tail.status();
    Say(absl::StrFormat("copied the tail of %s to %s (%llu batches in %.2f s with writes stopped)", m.map, m.to,
                        static_cast<unsigned long long>(tail->tail_batches()),
                        absl::ToDoubleSeconds(absl::Now() - start)));
    return absl::OkStatus();
  }

  void Say(const std::string& line) {
    base::MutexLock lock(&print_mutex_);
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }

  void PauseForTest() const {
    if (FILE* f = std::fopen(args_.pause_after_snapshot.c_str(), "w"); f != nullptr) {
      std::fputs("snapshots copied\n", f);
      std::fclose(f);
    }
    while (std::filesystem::exists(args_.pause_after_snapshot)) absl::SleepFor(absl::Milliseconds(20));
  }

  // Gives the run up when a copy failed, naming each failure.
  void ReportFailures(const std::vector<Move*>& todo, const std::vector<absl::Status>& statuses, const char* what) {
    bool failed = false;
    for (size_t i = 0; i < todo.size(); ++i) {
      if (statuses[i].ok()) continue;
      ReportCall(command_, todo[i]->from, absl::StrCat(what, todo[i]->map, " to ", todo[i]->to), statuses[i],
                 todo[i]->map);
      failed = true;
    }
    if (failed) GiveUp(todo);
  }

  // Undoes the copies not yet committed, so that the sources own their maps again (and take writes).
  void GiveUp(const std::vector<Move*>& todo) {
    for (const Move* m : todo) {
      if (m->copied) (void)fleet_.Of(m->to).DeleteMap(m->map, GlobalCall());
    }
    for (const Move* m : todo) {
      (void)fleet_.Of(m->from).SetMapMove(m->map, v1::MAP_MOVE_STEP_RESUME_WRITES, "", GlobalCall());
    }
    Fail("nothing was moved (the copies made are deleted, the maps take writes where they were); run this again "
         "once the cause is fixed");
  }

  void Commit(std::vector<Move>& moves) {
    for (Move& m : moves) {
      if (m.committed) continue;
      auto moved = fleet_.Of(m.from).SetMapMove(m.map, v1::MAP_MOVE_STEP_MOVED, m.to, GlobalCall());
      if (!moved.ok()) {
        ReportCall(command_, m.from, absl::StrCat("committing the move of map ", m.map), moved.status(), m.map);
        Fail("some maps are committed to their new owners and refuse writes where they were: run this again");
      }
      m.committed = true;
    }
  }

  // Each moved map asked for through the proxy until its new owner answers: the target's copy
  // serves, the old one is MOVED.
  void AwaitProxy(const std::vector<Move>& moves) const {
    const Fleet proxy(command_, {args_.proxy});
    const Client& client = proxy.Of(args_.proxy);
    const absl::Time give_up = absl::Now() + absl::Seconds(60);
    for (const Move& m : moves) {
      for (;;) {
        auto got = client.GetMap(m.map, GlobalCall());
        if (got.ok() && got->move_state() == v1::MAP_MOVE_STATE_SERVING) break;
        if (absl::Now() > give_up) {
          Fail(absl::StrCat("the proxy at ", args_.proxy, " still routes map ", m.map, " to ", m.from,
                            " after 60 s; the old copies are kept: check the proxy, then run this again"));
        }
        absl::SleepFor(absl::Milliseconds(100));
      }
    }
  }

  void Drop(const std::vector<Move>& moves) const {
    for (const Move& m : moves) {
      const absl::Status deleted = fleet_.Of(m.from).DeleteMap(m.map, GlobalCall());
      if (!deleted.ok() && !absl::IsNotFound(deleted)) {
        ReportCall(command_, m.from, absl::StrCat("deleting the old copy of map ", m.map), deleted, m.map);
        Fail("run this again to delete the old copies left");
      }
    }
  }

  const std::string command_;
  const MoveArgs& args_;
  const Fleet& fleet_;
  base::Mutex print_mutex_;  // the copies' lines, from several threads
};

// What to do with `map`, held by `source` (not its owner `owner`), given the owner's copy if any.
// nullopt: nothing to move (reported).
std::optional<Move> PlanOne(const std::string& command, const std::string& map, const std::string& source,
                            const v1::Map& source_copy, const std::string& owner,
                            const std::optional<v1::Map>& owner_copy) {
  Move m{map, source, owner};
  m.committed = source_copy.move_state() == v1::MAP_MOVE_STATE_MOVED;
  if (m.committed && !owner_copy) {
    std::fprintf(stderr, "fremenctl %s: map %s on %s says it moved to %s, but %s does not hold it; left as it is\n",
                 command.c_str(), map.c_str(), source.c_str(), source_copy.moved_to().c_str(), owner.c_str());
    return std::nullopt;
  }
  m.stale_target = !m.committed && owner_copy.has_value();
  m.source_stopped = source_copy.move_state() == v1::MAP_MOVE_STATE_WRITES_STOPPED;
  return m;
}

void RunRebalance(const MoveArgs& a) {
  const std::string command = "fleet rebalance";
  auto placement = Placement::Parse(a.daemons);
  if (!placement.ok()) FailUsage(command, absl::StrCat("--daemons: ", placement.status().message()));
  // The daemons asked: the new list, and any other --address names (daemons being removed).
  std::vector<std::string> asked = placement->daemons();
  if (NamesAFleet()) {
    for (const std::string& address : Addresses()) {
      if (absl::StartsWith(address, kEveryAddressPrefix)) {
        FailUsage(command, absl::StrCat("name the daemons one by one, not ", address));
      }
      if (std::find(asked.begin(), asked.end(), address) == asked.end()) asked.push_back(address);
    }
  }
  const Fleet fleet(command, asked);
  const FleetMaps held = ListFleetOrReport(command, fleet.client());
  if (!held.Unreachable().empty()) {
    FailCall(command, "planning", absl::UnavailableError("every daemon must answer before maps are moved"));
  }
  // Every copy of every map, by map.
  std::map<std::string, std::map<std::string, v1::Map>> copies;
  for (const FleetMap& copy : held.maps) copies[copy.map.name()][copy.daemon] = copy.map;
  std::vector<Move> moves;
  bool ambiguous = false;
  for (const auto& [name, on] : copies) {
    const std::string& owner = placement->Owner(name);
    std::optional<v1::Map> owner_copy;
    if (auto it = on.find(owner); it != on.end()) owner_copy = it->second;
    std::vector<std::string> others;
    for (const auto& [address, copy] : on) {
      if (address != owner) others.push_back(address);
    }
    if (others.empty()) {
      // On its owner. Writes left stopped (or a tail left recording) by a run that died before it
      // committed are resumed.
      if (owner_copy->move_state() == v1::MAP_MOVE_STATE_WRITES_STOPPED ||
          owner_copy->move_state() == v1::MAP_MOVE_STATE_COPYING) {
        (void)fleet.Of(owner).SetMapMove(name, v1::MAP_MOVE_STEP_RESUME_WRITES, "", GlobalCall());
      }
      continue;
    }
    if (others.size() > 1) {
      std::fprintf(stderr, "fremenctl %s: map %s is held by %s: move it by hand (fleet move)\n", command.c_str(),
                   name.c_str(), absl::StrJoin(others, ", ").c_str());
      ambiguous = true;
      continue;
    }
    auto m = PlanOne(command, name, others[0], on.at(others[0]), owner, owner_copy);
    if (m) {
      moves.push_back(*m);
    } else {
      ambiguous = true;
    }
  }
  Mover(command, a, fleet).Run(std::move(moves), placement->daemons());
  if (ambiguous) throw CLI::RuntimeError(kExitFailure);
}

void RunMove(const MoveArgs& a) {
  const std::string command = "fleet move";
  if (a.from == a.to) FailUsage(command, "--from and --to name the same daemon");
  const Fleet fleet(command, {a.from, a.to});
  auto source = CopyOn(fleet.Of(a.from), a.map);
  if (!source.ok()) FailCall(command, absl::StrCat("map ", a.map, " on ", a.from), source.status(), a.map);
  auto target = CopyOn(fleet.Of(a.to), a.map);
  if (!target.ok()) FailCall(command, absl::StrCat("map ", a.map, " on ", a.to), target.status(), a.map);
  if (!*source) {
    if (*target) {
      std::printf("map %s is on %s already\n", a.map.c_str(), a.to.c_str());
      return;
    }
    FailCall(command, absl::StrCat("map ", a.map), absl::NotFoundError(absl::StrCat("neither daemon holds it")), a.map);
  }
  auto m = PlanOne(command, a.map, a.from, **source, a.to, *target);
  if (!m) throw CLI::RuntimeError(kExitFailure);
  Mover(command, a, fleet).Run({*m}, {a.to});
}

void AddProxyOptions(CLI::App& app, MoveArgs& a) {
  app.add_option("--proxy-command", a.proxy_command,
                 "run (by /bin/sh) once the maps are copied and committed, before the old copies are deleted: it "
                 "must make the proxy route by the new daemon list (render deploy/nginx, nginx -s reload)");
  app.add_option("--proxy", a.proxy,
                 "the proxy's gRPC address: after --proxy-command, wait until it routes each moved map to its new "
                 "owner");
  app.add_flag("--proxy-reloaded", a.proxy_reloaded,
               "the proxy routes by the new daemon list already: delete the old copies (a run without "
               "--proxy-command stops before that)");
  app.add_option("--drain-seconds", a.drain_seconds,
                 "how long the old copies stay once the proxy routes to the new owners, for the proxy's connections "
                 "opened before its reload (they keep the old configuration until the proxy closes them)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_flag("--dry-run", a.dry_run, "only list the moves");
  // Hidden (no group): for tests (tests/fleet_online_move_test.cc).
  app.add_option("--test-pause-after-snapshot", a.pause_after_snapshot,
                 "test only: once the snapshots are copied, create FILE and wait until it is removed")
      ->group("");
}

}  // namespace

void RegisterFleetMoveCommands(CLI::App& fleet) {
  auto r = std::make_shared<MoveArgs>();
  CLI::App* rebalance = fleet.add_subcommand(
      "rebalance", "Move every map whose owner under the new daemon list is not the daemon that holds it");
  rebalance->add_option("--daemons", r->daemons,
                        "the fleet after the change, HOST:PORT,...: exactly the proxy's new `server` strings; every "
                        "one is asked for its maps (add daemons being removed with --address)")
      ->required();
  AddProxyOptions(*rebalance, *r);
  rebalance->add_option("--parallel", r->parallel, "maps copied at once (each daemon serves its exports and imports)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  rebalance->footer(
      "A moving map's snapshot is copied while its writers go on; then its writes stop and only the batches\n"
      "written meanwhile are copied. Its writers get UNAVAILABLE (\"map M is moving to another daemon; retry\")\n"
      "from then until the proxy routes to its new owner; queries go on. Run again after any failure "
      "(docs/fleet.md).");
  rebalance->callback([r] { RunRebalance(*r); });

  auto m = std::make_shared<MoveArgs>();
  CLI::App* move = fleet.add_subcommand("move", "Move one map from one daemon to another");
  move->add_option("--map", m->map, "the map")->required();
  move->add_option("--from", m->from, "the daemon that holds it, HOST:PORT")->required();
  move->add_option("--to", m->to, "the daemon to hold it, HOST:PORT")->required();
  AddProxyOptions(*move, *m);
  move->callback([m] { RunMove(*m); });
}

}  // namespace fremen::client
