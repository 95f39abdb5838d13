// Example: export a map's predicted occupancy at a time as a binary PGM image (one byte per cell,
// 255 = surely free as in map_server's convention, 0 = surely occupied).
//
//   export_region MAP TIME OUT.pgm [ADDRESS] [TOKEN]
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "client/lib/client.h"

namespace fc = fremen::client;

int main(int argc, char** argv) {
  if (argc < 4) return std::fprintf(stderr, "usage: export_region MAP TIME OUT.pgm [ADDRESS] [TOKEN]\n"), 2;
  const std::string map_name = argv[1];
  const double time = std::strtod(argv[2], nullptr);
  fc::ConnectionOptions options;
  if (argc > 4) options.address = argv[4];
  if (argc > 5) options.token = argv[5];
  auto client = fc::Client::Connect(options);
  if (!client.ok()) return std::fprintf(stderr, "%s\n", client.status().ToString().c_str()), 1;

  auto map = client->GetMap(map_name);
  if (!map.ok()) return std::fprintf(stderr, "GetMap: %s\n", map.status().ToString().c_str()), 1;
  if (map->kind() != fremen::v1::MAP_KIND_GRID) return std::fprintf(stderr, "%s is not a grid map\n", argv[1]), 1;

  // The bottom plane of the whole grid, as bytes round(255·p).
  fc::RegionQuery query;
  query.hi = {map->grid().size().x(), map->grid().size().y(), 1};
  query.time = time;
  query.output = fremen::v1::REGION_OUTPUT_UINT8;
  auto region = client->PredictRegion(map_name, query);
  if (!region.ok()) return std::fprintf(stderr, "PredictRegion: %s\n", region.status().ToString().c_str()), 1;

  std::ofstream out(argv[3], std::ios::binary);
  out << "P5\n" << region->shape.x << ' ' << region->shape.y << "\n255\n";
  // PGM rows go top down; the grid's y grows up.
  for (uint32_t y = region->shape.y; y-- > 0;) {
    for (uint32_t x = 0; x < region->shape.x; ++x) out.put(static_cast<char>(255 - region->bytes[region->Index(x, y)]));
  }
  if (!out) return std::fprintf(stderr, "cannot write %s\n", argv[3]), 1;
  std::printf("wrote %s: %u × %u cells at t = %.0f\n", argv[3], region->shape.x, region->shape.y, time);
  return 0;
}
