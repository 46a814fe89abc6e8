# We arrive here after a successful request: read the position out of the response.
position_x = result.result().x
position_y = result.result().y
