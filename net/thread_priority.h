#pragma once
// The robot link's threads (the client's keep-alives, the robot's deadman)
// are the safety chain: on a loaded machine they must not starve behind the
// window, the ghost or the fits (issue 59: a lease lost at load 10). The
// ghost and the fits run at nice 10; these ask for nice -5, which Linux
// grants to root or with CAP_SYS_NICE, and stay at 0 otherwise.

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace sp::net {

/// Raises the calling thread to nice -5 if allowed; true if it was.
inline bool raiseLinkThreadPriority() {
  return setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), -5) == 0;
}

}  // namespace sp::net
