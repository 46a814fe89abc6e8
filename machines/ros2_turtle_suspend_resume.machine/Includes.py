from llfsm import ros
