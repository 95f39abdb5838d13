// Compiled with the include paths of what links fremen_server: storage's private headers are not
// visible, so this must fail to compile (tests/layering/CMakeLists.txt).
#include "storage/shard.h"
