/*
 * The page's scripting: the script directory (GET /scripts.json, GET, PUT
 * and DELETE /scripts/NAME) and the script host (POST /script/run,
 * /script/stop).
 */
#include "impl.h"

enum MHD_Result wsg_web_serve_scripts(struct wsg_web *web,
                                      struct wsg_web_req *req)
{
    (void)web;
    return wsg_web_error(req->conn, MHD_HTTP_NOT_IMPLEMENTED,
                         "not yet served");
}

enum MHD_Result wsg_web_serve_script_file(struct wsg_web *web,
                                          struct wsg_web_req *req)
{
    (void)web;
    return wsg_web_error(req->conn, MHD_HTTP_NOT_IMPLEMENTED,
                         "not yet served");
}

enum MHD_Result wsg_web_serve_script_run(struct wsg_web *web,
                                         struct wsg_web_req *req)
{
    (void)web;
    return wsg_web_error(req->conn, MHD_HTTP_NOT_IMPLEMENTED,
                         "not yet served");
}
