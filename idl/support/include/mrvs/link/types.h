#pragma once
// Type supports of the wire types. The generated ones size every payload from the IDL
// bounds, so Fast DDS silently drops a received sample beyond them. The server reads
// requests with room for kMaxRaysReceived rays instead, so that an oversized batch from a
// broken or foreign client is answered with STATUS_TOO_MANY_RAYS rather than lost; larger
// samples are still dropped by the middleware (the server never allocates for them).
#include <cstddef>

#include <fastdds/dds/topic/TypeSupport.hpp>

namespace mrvs::link {

inline constexpr std::size_t kMaxRaysReceived = 1024;

/// RayQueryBatch type support whose payloads hold up to `max_rays` rays (same type name, so
/// it matches the generated one on the other side).
eprosima::fastdds::dds::TypeSupport request_type(std::size_t max_rays);

}  // namespace mrvs::link
