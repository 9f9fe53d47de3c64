// What the QDEM core needs of MPI, as an interface: the world and its domain
// (Domain.hpp) are compiled without MPI; MpiCommunicator.cpp implements it on
// a communicator duplicated from the one mpi4py hands over, so QDEM's
// messages never meet mpy's ANY_SOURCE probes.  A virtual call per message
// or collective, never per node.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace qdem {

class Communicator {
public:
    virtual ~Communicator() = default;
    virtual int rank() const = 0;
    virtual int size() const = 0;
    // Point to point with each neighbour (ascending): send[i] goes to
    // neighbours[i], recv[i] (already sized by the caller) comes from it.
    // One message per neighbour and direction; no ANY_SOURCE.
    virtual void exchange(const std::vector<int>& neighbours, const std::vector<std::vector<double>>& send,
                          std::vector<std::vector<double>>& recv) = 0;
    // As exchange, for messages whose size the receiver does not know: each
    // recv[i] is resized to what neighbours[i] sent (a probe on that rank,
    // never ANY_SOURCE).
    virtual void exchangeSized(const std::vector<int>& neighbours, const std::vector<std::vector<double>>& send,
                               std::vector<std::vector<double>>& recv) = 0;
    // Every rank's n values, in rank order, into all[size * n]: sums taken
    // from it in rank order are the same on every rank and every run.
    virtual void allgather(const double* mine, int n, double* all) = 0;
    // Every rank's byte block, in rank order (counts: bytes per rank).
    virtual void allgatherv(const std::vector<uint8_t>& mine, std::vector<uint8_t>& all, std::vector<int>& counts) = 0;
    // v[0..nSum) summed and v[nSum..nSum+nMax) maximised over the ranks,
    // the same bits on every rank and every run: a binomial tree of fixed
    // shape to rank 0, then a broadcast (2 log2 P messages, not P vectors).
    virtual void treeReduce(double* v, int nSum, int nMax) = 0;
    virtual void allreduceMax(double* v, int n) = 0;
    virtual void allreduceMin(double* v, int n) = 0;
    // Bytes and messages sent so far (the halo's counted cost).
    long bytesSent = 0, messagesSent = 0;
};

}  // namespace qdem
