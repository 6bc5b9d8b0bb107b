#include "cli/sigint.h"

namespace cablecal::cli {
namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void OnSigint(int) { g_interrupted = true; }

}  // namespace

std::atomic<bool>& SigintFlag() { return g_interrupted; }

SigintScope::SigintScope() {
  g_interrupted = false;
  struct sigaction action {};
  action.sa_handler = OnSigint;
  sigaction(SIGINT, &action, &previous_);
}

SigintScope::~SigintScope() { sigaction(SIGINT, &previous_, nullptr); }

}  // namespace cablecal::cli
