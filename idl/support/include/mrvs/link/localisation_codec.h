#pragma once
// The localisation service's wire form (idl/mrvs_link.idl: LocalisationRequest / Reply) to and
// from the plain types of mrvs::localisation, with the checks both ends apply. Submap points
// travel as int16 multiples of a quantum (6 bytes each) relative to the request's anchor, each
// with its image brightness (1 byte) when the edge measured it.
#include <cstddef>
#include <cstdint>

#include "mrvs/core/status.h"
#include "mrvs/localisation/types.h"
#include "mrvs_link.h"

namespace mrvs::link {

/// Points farther than 32767 quanta from the anchor on an axis are left out (counted in
/// *dropped), as are points beyond MAX_SUBMAP_POINTS.
wire::LocalisationRequest encode_localisation_request(std::uint32_t client_id,
                                                      const localisation::Request& request, float quantum_m,
                                                      std::size_t* dropped = nullptr);
/// The request as the cloud's localiser takes it; InvalidArgument naming the field for another
/// protocol version, a quantum that is not a finite positive number, too many points, a
/// non-finite anchor, gravity or prior.
StatusOr<localisation::Request> decode_localisation_request(const wire::LocalisationRequest& request);

/// The reply to `request` carrying `result`.
wire::LocalisationReply encode_localisation_reply(const wire::LocalisationRequest& request,
                                                  const localisation::Result& result);
/// A reply that refuses `request` (status, detail) without a pose.
wire::LocalisationReply refuse_localisation(const wire::LocalisationRequest& request,
                                            localisation::Status status, const std::string& detail);
/// DataLoss for another protocol version, a non-unit quaternion, non-finite values.
StatusOr<localisation::Result> decode_localisation_reply(const wire::LocalisationReply& reply);

/// CDR payload bytes of a sample (what the middleware sends, before the RTPS headers).
std::size_t payload_bytes(const wire::LocalisationRequest& request);
std::size_t payload_bytes(const wire::LocalisationReply& reply);

}  // namespace mrvs::link
