position_x = result.get()->x;
position_y = result.get()->y;
