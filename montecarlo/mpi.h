// montecarlo over MPI: one study on the P processes (ranks) of an MPI job (mpirun, srun),
// with OpenMP inside each rank. Every rank calls RunMonteCarloMpi with the same options;
// rank k makes the designed sets k, k+P, ... and runs the trial chunks of StudyShare{k, P};
// the designed sets are broadcast and rank 0 gathers every outcome, so its result is the
// single-process result to the bit, whatever P and the thread counts.
//
// Failures leave every rank knowing: rank 0 throws (SolverFailure when a designed set cannot
// be made, RankFailure naming each rank that could not finish its share and the cells it
// lost, Interrupted when any rank was interrupted), the other ranks throw AlreadyReported
// with the same exit code. A rank that dies outright (a signal, a lost node) makes the MPI
// launcher abort the whole job; rank 0 writes nothing before every share has arrived.
//
// Built only with CABLECAL_MPI=ON. Depends on MPI (Open MPI from Debian) and montecarlo.h.
#pragma once

#include "montecarlo/montecarlo.h"

namespace cablecal {

struct MpiWorld {
  int rank = 0;
  int size = 1;
};
MpiWorld WorldOf();  // MPI_COMM_WORLD; MPI must be initialised

// The whole result on rank 0; an empty result on the other ranks.
MonteCarloResult RunMonteCarloMpi(const Robot& nominal, const MonteCarloOptions& options);

// Test aid: with CABLECAL_TEST_FAIL_RANK=k in the environment, rank k fails its share with
// an exception (the run must report it and write nothing); with "k:crash" it aborts.
constexpr const char* kTestFailRankVariable = "CABLECAL_TEST_FAIL_RANK";

}  // namespace cablecal
