// How a phase sees the MPI domain (Domain.hpp): absent on one process, and
// not yet split before the first step under MPI.  The world owns the Domain;
// a phase holds this reference to the world's pointer, which setCommunicator
// may replace.
#pragma once
#include <memory>

#include "Domain.hpp"

namespace qdem {

struct DomainRef {
    const std::unique_ptr<Domain>& ptr;
    // The split domain, or nullptr (one process, or not split yet).
    Domain* built() const { return ptr && ptr->built() ? ptr.get() : nullptr; }
    // The domain, split or not, or nullptr on one process.
    Domain* any() const { return ptr.get(); }
};

}  // namespace qdem
