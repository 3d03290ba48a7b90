#include "mrvs/localisation/types.h"

namespace mrvs::localisation {

const char* status_name(Status status) {
  switch (status) {
    case Status::kOk:
      return "ok";
    case Status::kTooLittleStructure:
      return "too little structure";
    case Status::kAmbiguous:
      return "ambiguous";
    case Status::kOutsideMap:
      return "outside the map";
    case Status::kBadRequest:
      return "bad request";
    case Status::kMapUnavailable:
      return "map unavailable";
    case Status::kServerError:
      return "server error";
    case Status::kBusy:
      return "busy";
  }
  return "unknown";
}

}  // namespace mrvs::localisation
