#!/usr/bin/env bash
# Fails if anything under common/ includes or links the DDS middleware.
set -euo pipefail
root=${1:?usage: check_common_has_no_dds.sh REPO_ROOT}
hits=$(grep -rnE '#\s*include\s*[<"](fastdds|fastrtps|fastcdr)/|#\s*include\s*[<"][^">]*PubSubTypes' \
         "$root/common" --include='*.h' --include='*.hpp' --include='*.cpp' --include='*.cc' || true)
links=$(grep -rnE '\b(fastrtps|fastcdr|mrvs::idl|mrvs_idl)\b' "$root/common" --include='CMakeLists.txt' || true)
if [[ -n "$hits$links" ]]; then
  echo "common/ must not depend on Fast DDS (move DDS code to cloud_server/ or edge_client/):"
  [[ -n "$hits" ]] && echo "$hits"
  [[ -n "$links" ]] && echo "$links"
  exit 1
fi
echo "common/ is middleware-free"
