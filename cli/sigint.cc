#include "cli/sigint.h"

namespace cablecal::cli {
namespace {

std::atomic<bool> g_interrupted{false};
int g_depth = 0;  // scopes nest: reproduce holds one across its phases, each study another
extern "C" void OnSigint(int) { g_interrupted = true; }

}  // namespace

std::atomic<bool>& SigintFlag() { return g_interrupted; }

SigintScope::SigintScope() {
  if (g_depth++ > 0) return;  // an inner scope keeps what the outer one has seen
  g_interrupted = false;
  struct sigaction action {};
  action.sa_handler = OnSigint;
  sigaction(SIGINT, &action, &previous_);
}

SigintScope::~SigintScope() {
  if (--g_depth == 0) sigaction(SIGINT, &previous_, nullptr);
}

}  // namespace cablecal::cli
