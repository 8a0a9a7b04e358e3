#include "app/shutdown_request.hpp"

#include <csignal>

namespace probelight {
namespace {

volatile std::sig_atomic_t g_shutdown_signal = 0;

extern "C" void recordShutdownSignal(int signal_number) { g_shutdown_signal = signal_number; }

}  // namespace

void installShutdownHandlers() {
  struct sigaction action {};
  action.sa_handler = recordShutdownSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a blocking wait returns early
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
}

int shutdownSignal() { return g_shutdown_signal; }

void clearShutdownRequest() { g_shutdown_signal = 0; }

}  // namespace probelight
