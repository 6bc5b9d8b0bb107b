// Ctrl-C for the long commands (design, montecarlo, reproduce): while a SigintScope lives,
// SIGINT sets SigintFlag() instead of ending the process, and the command stops at its next
// check (a Monte Carlo trial, an Ipopt iteration, a phase of reproduce), writes nothing and
// exits 130. Scopes nest; the outermost one installs the handler and clears the flag.
#pragma once

#include <atomic>
#include <csignal>

namespace cablecal::cli {

std::atomic<bool>& SigintFlag();

class SigintScope {
 public:
  SigintScope();
  ~SigintScope();
  SigintScope(const SigintScope&) = delete;
  SigintScope& operator=(const SigintScope&) = delete;

 private:
  struct sigaction previous_ {};
};

}  // namespace cablecal::cli
