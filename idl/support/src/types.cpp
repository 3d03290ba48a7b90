#include "mrvs/link/types.h"

#include "mrvs_linkPubSubTypes.h"

namespace mrvs::link {
namespace {

class ResizedRequestType : public wire::RayQueryBatchPubSubType {
 public:
  explicit ResizedRequestType(std::size_t max_rays) {
    // encapsulation 4 + seq 8 + stamp 8 + client 4 + sequence length 4 + 32 per ray
    // + want_normals 1, padded to 4
    m_typeSize = static_cast<std::uint32_t>(4 + 8 + 8 + 4 + 4 + 32 * max_rays + 4);
  }
};

}  // namespace

eprosima::fastdds::dds::TypeSupport request_type(std::size_t max_rays) {
  return eprosima::fastdds::dds::TypeSupport(new ResizedRequestType(max_rays));
}

}  // namespace mrvs::link
