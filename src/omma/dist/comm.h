// Process groups for distributed jobs: MPI when the program was started by mpirun (and omma was
// built with OMMA_MPI), otherwise one local process. The job layer (job.h) talks only to Comm, so
// the same code path runs with and without MPI.
//
// Messages are byte strings (std::string as a buffer: JSON text for control messages, raw pixels
// for image bands). Only the thread that created the Comm may call it (MPI_THREAD_FUNNELED).
// Waiting is done by polling (probe, then sleep): OpenMPI's blocking calls spin a core, which on an
// oversubscribed machine (more ranks than cores) would take CPU from the ranks that work.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace omma::dist {

struct Message {
  int source = -1;
  int tag = 0;
  std::string data;
};

class Comm {
 public:
  virtual ~Comm() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  virtual bool is_mpi() const = 0;
  virtual std::string host() const;  // this process's host name (for messages and manifests)

  // Point to point (rank != this rank). send() returns once `data` may be reused.
  virtual void send(int dest, int tag, const std::string& data) = 0;
  // A pending message from any rank, if there is one (does not block).
  virtual std::optional<Message> try_recv() = 0;
  // Waits for a message from any rank: polls try_recv(), sleeping `poll` between attempts.
  Message recv(std::chrono::microseconds poll = std::chrono::microseconds(500));

  // Collectives: every rank must call them in the same order.
  // Rank 0's `data` on every rank.
  virtual std::string broadcast(const std::string& data) = 0;
  // Every rank's `data`, in rank order, on rank 0 (empty vector on the others).
  virtual std::vector<std::string> gather(const std::string& data) = 0;

  // Ends every rank at once (MPI_Abort) after a failure on this rank that the others cannot know
  // of; one process: exits.
  [[noreturn]] virtual void abort(int code) = 0;
};

// A single process: rank 0 of 1. Point-to-point calls throw (there is no other rank).
class LocalComm : public Comm {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  bool is_mpi() const override { return false; }
  void send(int dest, int tag, const std::string& data) override;
  std::optional<Message> try_recv() override { return std::nullopt; }
  std::string broadcast(const std::string& data) override { return data; }
  std::vector<std::string> gather(const std::string& data) override { return {data}; }
  [[noreturn]] void abort(int code) override;
};

// True when this process was started by an MPI launcher (OpenMPI's mpirun, or a PMI/PMIx launcher
// such as srun): the launcher sets OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK. *size gets the
// number of processes when the launcher says it (0 otherwise).
bool launched_by_mpi(int* size = nullptr);

// Whether this build has MPI (CMake option OMMA_MPI).
bool built_with_mpi();

// MPI (MPI_Init_thread, FUNNELED; MPI_Finalize in the destructor) when launched by mpirun, else a
// LocalComm. Throws std::runtime_error when launched by mpirun with several processes but built
// without MPI (each process would do the whole job on its own). At most one per process.
std::unique_ptr<Comm> make_comm();

}  // namespace omma::dist
