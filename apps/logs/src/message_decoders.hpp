// The per-serialization decoders behind messages.cpp.
#pragma once

#include "fgcal/logs/messages.hpp"

namespace fgcal::logs::detail {

// ROS 1 wire format (ros1_messages.cpp). `where` names topic and message for errors.
JointState decodeRos1JointState(const RawMessage& m, const std::string& file, const std::string& where);
Image decodeRos1Image(const RawMessage& m, const std::string& file, const std::string& where);
CompressedImage decodeRos1CompressedImage(const RawMessage& m, const std::string& file, const std::string& where);
CameraInfo decodeRos1CameraInfo(const RawMessage& m, const std::string& file, const std::string& where);
std::int64_t decodeRos1HeaderStamp(const RawMessage& m, const std::string& file, const std::string& where);

// CDR / XCDR1 (cdr_messages.cpp).
JointState decodeCdrJointState(const RawMessage& m, const std::string& file, const std::string& where);
Image decodeCdrImage(const RawMessage& m, const std::string& file, const std::string& where);
CompressedImage decodeCdrCompressedImage(const RawMessage& m, const std::string& file, const std::string& where);
CameraInfo decodeCdrCameraInfo(const RawMessage& m, const std::string& file, const std::string& where);
std::int64_t decodeCdrHeaderStamp(const RawMessage& m, const std::string& file, const std::string& where);

}  // namespace fgcal::logs::detail
