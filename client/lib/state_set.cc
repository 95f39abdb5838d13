#include "client/lib/state_set.h"

namespace fremen::client {

v1::StateRef State::AtCell(Cell cell) {
  v1::StateRef ref;
  ref.mutable_cell()->set_x(cell.x);
  ref.mutable_cell()->set_y(cell.y);
  ref.mutable_cell()->set_z(cell.z);
  return ref;
}

v1::StateRef State::AtPoint(Point point) {
  v1::StateRef ref;
  ref.mutable_point()->set_x(point.x);
  ref.mutable_point()->set_y(point.y);
  ref.mutable_point()->set_z(point.z);
  return ref;
}

v1::StateRef State::WithId(uint64_t id) {
  v1::StateRef ref;
  ref.set_id(id);
  return ref;
}

v1::StateRef State::Named(std::string name) {
  v1::StateRef ref;
  ref.set_name(std::move(name));
  return ref;
}

StateSet StateSet::Cells(const std::vector<Cell>& cells) {
  StateSet set;
  v1::CellIndices* out = set.refs_.mutable_cells();
  for (const Cell& c : cells) {
    out->add_x(c.x);
    out->add_y(c.y);
    out->add_z(c.z);
  }
  set.size_ = cells.size();
  return set;
}

StateSet StateSet::Points(const std::vector<Point>& points) {
  StateSet set;
  v1::Points* out = set.refs_.mutable_points();
  for (const Point& p : points) {
    out->add_x(p.x);
    out->add_y(p.y);
    out->add_z(p.z);
  }
  set.size_ = points.size();
  return set;
}

StateSet StateSet::Ids(const std::vector<uint64_t>& ids) {
  StateSet set;
  set.refs_.mutable_ids()->Assign(ids.begin(), ids.end());
  set.size_ = ids.size();
  return set;
}

StateSet StateSet::Names(const std::vector<std::string>& names) {
  StateSet set;
  for (const std::string& name : names) set.refs_.add_names(name);
  set.size_ = names.size();
  return set;
}

}  // namespace fremen::client
