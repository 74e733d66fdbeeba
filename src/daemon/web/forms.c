/*
 * The page's motion: the forms public code posts (POST /motion.json and
 * POST /graspconf.json with the numbered fields of the real gripper's
 * page) and the Motion tab's buttons (POST /motion).
 */
#include "impl.h"

enum MHD_Result wsg_web_serve_motion_form(struct wsg_web *web,
                                          struct wsg_web_req *req)
{
    (void)web;
    return wsg_web_error(req->conn, MHD_HTTP_NOT_IMPLEMENTED,
                         "not yet served");
}

enum MHD_Result wsg_web_serve_graspconf(struct wsg_web *web,
                                        struct wsg_web_req *req)
{
    (void)web;
    return wsg_web_error(req->conn, MHD_HTTP_NOT_IMPLEMENTED,
                         "not yet served");
}

enum MHD_Result wsg_web_serve_motion(struct wsg_web *web,
                                     struct wsg_web_req *req)
{
    (void)web;
    return wsg_web_error(req->conn, MHD_HTTP_NOT_IMPLEMENTED,
                         "not yet served");
}
