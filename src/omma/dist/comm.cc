#include "omma/dist/comm.h"

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <thread>

#include <fmt/format.h>

#ifdef OMMA_HAVE_MPI
#include <mpi.h>
#endif

namespace omma::dist {

std::string Comm::host() const {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "?";
  return name;
}

Message Comm::recv(std::chrono::microseconds poll) {
  for (;;) {
    if (auto m = try_recv()) return std::move(*m);
    std::this_thread::sleep_for(poll);
  }
}

void LocalComm::send(int dest, int, const std::string&) {
  throw std::logic_error(fmt::format("LocalComm: no rank {} to send to (one process)", dest));
}

void LocalComm::abort(int code) { std::exit(code); }

bool launched_by_mpi(int* size) {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"}) {
    if (const char* v = std::getenv(var)) {
      if (size) *size = std::string(var) == "PMIX_RANK" ? 0 : std::atoi(v);
      return true;
    }
  }
  if (size) *size = 0;
  return false;
}

#ifdef OMMA_HAVE_MPI
bool built_with_mpi() { return true; }

namespace {

constexpr auto kPoll = std::chrono::microseconds(200);

// Completes a non-blocking request without spinning a core (see comm.h).
void wait_polling(MPI_Request* req) {
  for (;;) {
    int done = 0;
    MPI_Test(req, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(kPoll);
  }
}

class MpiComm : public Comm {
 public:
  MpiComm() {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiComm() override {
    // Every rank gets here (normally or after a reported error); a polled barrier keeps the ranks
    // that finish first from spinning in MPI_Finalize while rank 0 writes the manifest.
    MPI_Request req;
    MPI_Ibarrier(MPI_COMM_WORLD, &req);
    wait_polling(&req);
    MPI_Finalize();
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  bool is_mpi() const override { return true; }

  void send(int dest, int tag, const std::string& data) override {
    MPI_Request req;
    MPI_Isend(data.data(), static_cast<int>(data.size()), MPI_BYTE, dest, tag, MPI_COMM_WORLD, &req);
    wait_polling(&req);
  }

  std::optional<Message> try_recv() override {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
    if (!flag) return std::nullopt;
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    Message m;
    m.source = st.MPI_SOURCE;
    m.tag = st.MPI_TAG;
    m.data.resize(count);
    MPI_Recv(m.data.data(), count, MPI_BYTE, m.source, m.tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return m;
  }

  std::string broadcast(const std::string& data) override {
    uint64_t n = data.size();
    MPI_Request req;
    MPI_Ibcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD, &req);
    wait_polling(&req);
    std::string out = rank_ == 0 ? data : std::string(n, '\0');
    MPI_Ibcast(out.data(), static_cast<int>(n), MPI_BYTE, 0, MPI_COMM_WORLD, &req);
    wait_polling(&req);
    return out;
  }

  std::vector<std::string> gather(const std::string& data) override {
    int n = static_cast<int>(data.size());
    std::vector<int> counts(rank_ == 0 ? size_ : 0), displs(counts.size());
    MPI_Request req;
    MPI_Igather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD, &req);
    wait_polling(&req);
    std::string all;
    if (rank_ == 0) {
      int total = 0;
      for (int r = 0; r < size_; ++r) {
        displs[r] = total;
        total += counts[r];
      }
      all.resize(total);
    }
    MPI_Igatherv(data.data(), n, MPI_BYTE, all.data(), counts.data(), displs.data(), MPI_BYTE, 0,
                 MPI_COMM_WORLD, &req);
    wait_polling(&req);
    std::vector<std::string> out;
    for (size_t r = 0; r < counts.size(); ++r) out.push_back(all.substr(displs[r], counts[r]));
    return out;
  }

  [[noreturn]] void abort(int code) override {
    MPI_Abort(MPI_COMM_WORLD, code);
    std::_Exit(code);
  }

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace

std::unique_ptr<Comm> make_comm() {
  if (launched_by_mpi()) return std::make_unique<MpiComm>();
  return std::make_unique<LocalComm>();
}

#else  // no MPI in this build

bool built_with_mpi() { return false; }

std::unique_ptr<Comm> make_comm() {
  int n = 0;
  if (launched_by_mpi(&n) && n > 1)
    throw std::runtime_error(fmt::format(
        "started by mpirun with {} processes, but this omma was built without MPI (configure with OpenMPI "
        "installed, or -DOMMA_MPI=ON); run it as one process",
        n));
  return std::make_unique<LocalComm>();
}

#endif

}  // namespace omma::dist
