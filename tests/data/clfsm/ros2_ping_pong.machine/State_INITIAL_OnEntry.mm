int argc = 1; static char *argv[1];
std::string node_name="ros_ping_pong";
char * cstr = new char [node_name.length()+1];
std::strcpy (cstr, node_name.c_str());
argv[0]= cstr;
rclcpp::init(argc, argv);
node = rclcpp::Node::make_shared(node_name);
publisher_ = node->create_publisher<std_msgs::msg::String>("pingpong", 10);
count=0;
