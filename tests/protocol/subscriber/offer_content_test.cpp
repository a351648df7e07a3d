#include "protocol/subscriber/offer_content.h"

#include <gtest/gtest.h>

#include "protocol/subscriber/multicast_datagram.h"
#include "support/subscriber_fixture.h"

namespace skinstream::subscriber {
namespace {

using test::payload_of;
using test::subscriber_fixture;

std::vector<unsigned char> golden_offer() {
  return encode_offer(subscriber_fixture("packed_mesh_info_v2.bin"), subscriber_fixture("packed_model.bin"));
}

uint32_t golden_model_id() { return model_id_of(payload_of(subscriber_fixture("model.bin"))); }

std::string refusal(std::span<const unsigned char> offer, uint32_t model_id) {
  try {
    decode_offer(offer, model_id);
    return "accepted";
  } catch (const DecodeError& e) {
    return e.what();
  }
}

TEST(OfferContent, HoldsWhatAPackedParameterSubscriberIsSentAsItJoins) {
  const std::vector<unsigned char> offer = golden_offer();
  const OfferContent content = decode_offer(offer, golden_model_id());
  EXPECT_EQ(content.mesh_info.type, MessageType::MeshInfo);
  EXPECT_EQ(content.model.type, MessageType::Model);
  const std::vector<unsigned char> mesh_info = subscriber_fixture("mesh_info_v2.bin"),
                                   model = subscriber_fixture("model.bin");
  EXPECT_EQ(content.mesh_info.payload,
            std::vector<unsigned char>(payload_of(mesh_info).begin(), payload_of(mesh_info).end()));
  EXPECT_EQ(content.model.payload,
            std::vector<unsigned char>(payload_of(model).begin(), payload_of(model).end()));
}

TEST(OfferContent, AnOfferThatIsNotOneSubjectsIsRefusedWithTheReason) {
  const std::vector<unsigned char> offer = golden_offer();
  const std::vector<unsigned char> mesh_info = subscriber_fixture("packed_mesh_info_v2.bin"),
                                   model = subscriber_fixture("packed_model.bin");
  // The Model of another subject than the frames' (or a forger's).
  EXPECT_NE(refusal(offer, golden_model_id() ^ 1).find("and its datagrams say"), std::string::npos);
  // Its messages the other way round, twice the same, or plain.
  EXPECT_NE(refusal(encode_offer(model, mesh_info), golden_model_id())
                .find("packed Model where its MeshInfo belongs"),
            std::string::npos);
  EXPECT_NE(refusal(encode_offer(mesh_info, mesh_info), golden_model_id())
                .find("packed MeshInfo where its Model belongs"),
            std::string::npos);
  EXPECT_NE(refusal(encode_offer(subscriber_fixture("mesh_info_v2.bin"), model), golden_model_id())
                .find("where a version 2 Packed"),
            std::string::npos);
  // Cut short anywhere, or with bytes after it.
  for (size_t keep : {size_t{0}, size_t{5}, mesh_info.size() - 1, mesh_info.size(), mesh_info.size() + 13,
                      offer.size() - 1}) {
    const std::string why = refusal(std::span(offer).first(keep), golden_model_id());
    EXPECT_NE(why, "accepted") << keep;
    EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  }
  std::vector<unsigned char> longer = offer;
  longer.push_back(0);
  EXPECT_NE(refusal(longer, golden_model_id()).find("1 bytes after the offer's Model"), std::string::npos);
}

}  // namespace
}  // namespace skinstream::subscriber
