/*
 * The page's settings (GET and POST /settings.json).
 */
#include "impl.h"

enum MHD_Result wsg_web_serve_settings(struct wsg_web *web,
                                       struct wsg_web_req *req)
{
    (void)web;
    return wsg_web_error(req->conn, MHD_HTTP_NOT_IMPLEMENTED,
                         "not yet served");
}
