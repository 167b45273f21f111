/* placeholder */
#include "app.h"
static http_resp placeholder(http_req *req) { (void)req; return http_problem(501, NULL, "not implemented yet"); }
const http_route api_scenes_routes[] = {{"GET", "/api/v1/_scenes", placeholder}};
const int api_scenes_nroutes = 1;
