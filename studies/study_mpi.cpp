#include "studies/study_mpi.h"

#include "basics/errors.h"
#include "basics/parallel.h"

#include <mpi.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <thread>

#include <unistd.h>

namespace armsim {

namespace {

constexpr int kRequestTag = 1, kWorkTag = 2;
constexpr auto kPollPause = std::chrono::microseconds(500);

void check(int code, const char* what) {
    if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

bool probeMessage(int source, int tag, MPI_Status& status) {
    int flag = 0;
    check(MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, &status), "MPI_Iprobe");
    return flag != 0;
}

std::string receiveProbed(const MPI_Status& probed, int tag) {
    int size = 0;
    check(MPI_Get_count(&probed, MPI_CHAR, &size), "MPI_Get_count");
    std::string message(std::size_t(size), '\0');
    check(MPI_Recv(message.data(), size, MPI_CHAR, probed.MPI_SOURCE, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "MPI_Recv");
    return message;
}

void sendTo(int rank, int tag, const std::string& message) {
    check(MPI_Send(message.data(), int(message.size()), MPI_CHAR, rank, tag, MPI_COMM_WORLD), "MPI_Send");
}

class Coordinator : public StudyCoordinatorLink {
public:
    explicit Coordinator(int size) : size_(size) {}
    int getNumWorkers() const override { return size_ - 1; }
    bool receive(int& worker, std::string& message) override {
        MPI_Status status;
        if (!probeMessage(MPI_ANY_SOURCE, kRequestTag, status)) return false;
        worker = status.MPI_SOURCE;
        message = receiveProbed(status, kRequestTag);
        return true;
    }
    void send(int worker, const std::string& message) override { sendTo(worker, kWorkTag, message); }

private:
    int size_;
};

class Worker : public StudyWorkerLink {
public:
    explicit Worker(int rank) : rank_(rank) {}
    int getRank() const override { return rank_; }
    std::string exchange(const std::string& message) override {
        sendTo(0, kRequestTag, message);
        MPI_Status status;
        while (!probeMessage(0, kWorkTag, status)) std::this_thread::sleep_for(kPollPause);
        return receiveProbed(status, kWorkTag);
    }

private:
    int rank_;
};

}  // namespace

std::optional<std::pair<Study, StudyOutcome>> runStudyOnMpi(const std::string& studyFile, const StudyRunOptions& options) {
    // Shared-memory transfers through CMA need ptrace rights that containers often lack; copy-in/out
    // costs nothing at these message sizes. A user's own setting wins.
    setenv("OMPI_MCA_btl_vader_single_copy_mechanism", "none", 0);
    int provided = 0;
    check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    if (provided < MPI_THREAD_FUNNELED) {
        std::fprintf(stderr, "error: this MPI library cannot host threads (MPI_THREAD_FUNNELED not provided)\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    StudyRunOptions o = options;
    if (o.threads <= 0) {  // this rank's CPUs (mpirun's or srun's binding), shared with its node's ranks
        MPI_Comm node;
        int localRanks = 1;
        check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &node),
              "MPI_Comm_split_type");
        MPI_Comm_size(node, &localRanks);
        MPI_Comm_free(&node);
        o.threads = calcThreadsPerRank(getNumUsableCpus(), int(sysconf(_SC_NPROCESSORS_ONLN)), localRanks);
    }
    std::optional<std::pair<Study, StudyOutcome>> outcome;
    try {
        const Study study = readStudy(studyFile);
        if (rank == 0) {
            Coordinator link(size);
            outcome.emplace(study, runStudy(study, o, &link));
        } else {
            Worker link(rank);
            runStudyWorker(study, o.threads, link);
        }
    } catch (const InterruptedError& e) {
        std::fprintf(stderr, "rank %d: %s; the journal keeps every finished group\n", rank, e.what());
        std::fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, 128 + getInterruption());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error (rank %d): %s\n", rank, e.what());
        std::fflush(stderr);
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    MPI_Finalize();
    return outcome;
}

}  // namespace armsim

extern "C" __attribute__((visibility("default"))) const armsim::StudyMpiPlugin* armsim_get_study_mpi_plugin() {
    static const armsim::StudyMpiPlugin plugin{armsim::kStudyMpiPluginAbi, &armsim::runStudyOnMpi,
                                               &armsim::requestInterruption};
    return &plugin;
}
