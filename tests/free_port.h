// Loopback ports for test daemons and proxies that must be named before they start (a fleet's
// placement, a daemon restarted on its address, nginx's configuration).
#pragma once

#include <string>

namespace fremen::testing {

// "127.0.0.1:PORT", a port that no other caller gets while this process lives. It is taken below
// the kernel's ephemeral range (net.ipv4.ip_local_port_range): a port handed out there and released
// could be given to any bind to port 0 — every other test's daemon — before its user binds it, and
// a proxy whose listen then fails would leave the test talking to a stranger. Test processes
// running side by side (ctest -j) share the range through a lock file per port, held until exit.
std::string FreeLoopbackAddress();

}  // namespace fremen::testing
