// Communicator (Communicator.hpp) on Open MPI.  Built only when MPI is found
// (CMake option QDEM_WITH_MPI); the core itself never includes mpi.h.
#pragma once
#include <mpi.h>

#include "Communicator.hpp"

namespace qdem {

class MpiCommunicator final : public Communicator {
public:
    // Duplicates `comm` (mpi4py's, or MPI_COMM_WORLD): QDEM's messages then
    // live in their own context and never match anyone else's receives.
    explicit MpiCommunicator(MPI_Comm comm);
    ~MpiCommunicator() override;
    MpiCommunicator(const MpiCommunicator&) = delete;
    MpiCommunicator& operator=(const MpiCommunicator&) = delete;

    int rank() const override { return rank_; }
    int size() const override { return size_; }
    void exchange(const std::vector<int>& neighbours, const std::vector<std::vector<double>>& send,
                  std::vector<std::vector<double>>& recv) override;
    void exchangeSized(const std::vector<int>& neighbours, const std::vector<std::vector<double>>& send,
                       std::vector<std::vector<double>>& recv) override;
    void allgather(const double* mine, int n, double* all) override;
    void allgatherv(const std::vector<uint8_t>& mine, std::vector<uint8_t>& all, std::vector<int>& counts) override;
    void treeReduce(double* v, int nSum, int nMax) override;
    void allreduceMax(double* v, int n) override;
    void allreduceMin(double* v, int n) override;

private:
    MPI_Comm comm_ = MPI_COMM_NULL;
    int rank_ = 0, size_ = 1;
    std::vector<MPI_Request> requests_;
    std::vector<double> treeBuf_;
};

}  // namespace qdem
