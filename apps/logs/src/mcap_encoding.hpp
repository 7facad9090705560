// How an MCAP channel whose message_encoding is not "cdr" (json, protobuf,
// ros1, ...) is listed: TopicInfo has no field for the encoding, so the
// reader appends it to the type ("sensor_msgs/msg/Image (message encoding
// json)"). The topic stays listed and readable as raw bytes; messageKind()
// sees no sensor_msgs type in it, and the CDR decoders refuse it naming the
// encoding instead of misreading foreign bytes as CDR.
#pragma once

#include <string>

namespace fgcal::logs::detail {

inline std::string typeWithForeignEncoding(const std::string& type, const std::string& encoding) {
  return type + " (message encoding " + encoding + ")";
}

/// The encoding carried by such a type, or "" for an ordinary type.
inline std::string foreignEncodingOf(const std::string& type) {
  static const std::string marker = " (message encoding ";
  const auto at = type.rfind(marker);
  if (at == std::string::npos || type.empty() || type.back() != ')') return {};
  return type.substr(at + marker.size(), type.size() - 1 - at - marker.size());
}

}  // namespace fgcal::logs::detail
