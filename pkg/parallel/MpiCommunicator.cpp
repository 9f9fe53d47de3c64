#include "MpiCommunicator.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace qdem {

namespace {
constexpr int kHaloTag = 0x5144;   // "QD"; the duplicated communicator keeps it apart anyway
constexpr int kSizedTag = 0x5145;  // messages of unknown size (contact halo)
constexpr int kTreeTag = 0x5146;   // the end-of-step reduction

void check(int rc, const char* what) {
    if (rc != MPI_SUCCESS) throw std::runtime_error(std::string("QDEM MPI: ") + what + " failed");
}
}  // namespace

MpiCommunicator::MpiCommunicator(MPI_Comm comm) {
    int ok = 0;
    MPI_Initialized(&ok);
    if (!ok) throw std::runtime_error("QDEM MPI: MPI is not initialised (import mpi4py.MPI first)");
    check(MPI_Comm_dup(comm, &comm_), "MPI_Comm_dup");
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &size_);
}

MpiCommunicator::~MpiCommunicator() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized && comm_ != MPI_COMM_NULL) MPI_Comm_free(&comm_);
}

void MpiCommunicator::exchange(const std::vector<int>& neighbours, const std::vector<std::vector<double>>& send,
                               std::vector<std::vector<double>>& recv) {
    const std::size_t nb = neighbours.size();
    requests_.assign(2 * nb, MPI_REQUEST_NULL);
    // Receives posted first, then the sends; all complete together.  Empty
    // ones are skipped on both sides (the lists are symmetric: a rank sends
    // nothing exactly where its neighbour expects nothing).
    for (std::size_t i = 0; i < nb; ++i)
        if (!recv[i].empty())
            check(MPI_Irecv(recv[i].data(), static_cast<int>(recv[i].size()), MPI_DOUBLE, neighbours[i], kHaloTag, comm_,
                        &requests_[i]),
              "MPI_Irecv");
    for (std::size_t i = 0; i < nb; ++i) {
        if (send[i].empty()) continue;
        check(MPI_Isend(send[i].data(), static_cast<int>(send[i].size()), MPI_DOUBLE, neighbours[i], kHaloTag, comm_,
                        &requests_[nb + i]),
              "MPI_Isend");
        bytesSent += static_cast<long>(send[i].size() * sizeof(double));
        ++messagesSent;
    }
    check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
}

void MpiCommunicator::exchangeSized(const std::vector<int>& neighbours, const std::vector<std::vector<double>>& send,
                                    std::vector<std::vector<double>>& recv) {
    const std::size_t nb = neighbours.size();
    requests_.assign(nb, MPI_REQUEST_NULL);
    // Every neighbour gets a message, empty or not: the receiver cannot know.
    for (std::size_t i = 0; i < nb; ++i) {
        check(MPI_Isend(send[i].data(), static_cast<int>(send[i].size()), MPI_DOUBLE, neighbours[i], kSizedTag, comm_,
                        &requests_[i]),
              "MPI_Isend");
        bytesSent += static_cast<long>(send[i].size() * sizeof(double));
        ++messagesSent;
    }
    for (std::size_t i = 0; i < nb; ++i) {
        MPI_Status st;
        check(MPI_Probe(neighbours[i], kSizedTag, comm_, &st), "MPI_Probe");
        int count = 0;
        MPI_Get_count(&st, MPI_DOUBLE, &count);
        recv[i].resize(count);
        check(MPI_Recv(recv[i].data(), count, MPI_DOUBLE, neighbours[i], kSizedTag, comm_, MPI_STATUS_IGNORE),
              "MPI_Recv");
    }
    check(MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
}

void MpiCommunicator::allgather(const double* mine, int n, double* all) {
    check(MPI_Allgather(mine, n, MPI_DOUBLE, all, n, MPI_DOUBLE, comm_), "MPI_Allgather");
}

void MpiCommunicator::allgatherv(const std::vector<uint8_t>& mine, std::vector<uint8_t>& all, std::vector<int>& counts) {
    const int n = static_cast<int>(mine.size());
    counts.assign(size_, 0);
    check(MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, comm_), "MPI_Allgather");
    std::vector<int> displ(size_, 0);
    for (int r = 1; r < size_; ++r) displ[r] = displ[r - 1] + counts[r - 1];
    all.resize(static_cast<std::size_t>(displ[size_ - 1]) + counts[size_ - 1]);
    check(MPI_Allgatherv(mine.data(), n, MPI_BYTE, all.data(), counts.data(), displ.data(), MPI_BYTE, comm_),
          "MPI_Allgatherv");
}

void MpiCommunicator::treeReduce(double* v, int nSum, int nMax) {
    const int n = nSum + nMax;
    treeBuf_.resize(n);
    // Rank r takes in, for k = 1, 2, 4, ... while r is a multiple of 2k,
    // the partial of rank r + k (if there is one), then sends its own to
    // r - (r mod 2k): the tree and the order of every sum are fixed by P.
    for (int k = 1; k < size_; k *= 2) {
        if (rank_ % (2 * k) == 0) {
            if (rank_ + k < size_) {
                check(MPI_Recv(treeBuf_.data(), n, MPI_DOUBLE, rank_ + k, kTreeTag, comm_, MPI_STATUS_IGNORE),
                      "MPI_Recv");
                for (int i = 0; i < nSum; ++i) v[i] += treeBuf_[i];
                for (int i = nSum; i < n; ++i) v[i] = std::max(v[i], treeBuf_[i]);
            }
        } else {
            check(MPI_Send(v, n, MPI_DOUBLE, rank_ - k, kTreeTag, comm_), "MPI_Send");
            bytesSent += static_cast<long>(n * sizeof(double));
            ++messagesSent;
            break;
        }
    }
    check(MPI_Bcast(v, n, MPI_DOUBLE, 0, comm_), "MPI_Bcast");
}

void MpiCommunicator::allreduceMax(double* v, int n) {
    check(MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_MAX, comm_), "MPI_Allreduce");
}

void MpiCommunicator::allreduceMin(double* v, int n) {
    check(MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_MIN, comm_), "MPI_Allreduce");
}

}  // namespace qdem
