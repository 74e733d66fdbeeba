-- public_style.lua: a command-and-measure script written the way the
-- published gripper scripts are written, not the way the project writes
-- its own: the socket module made a global by a bare `require "socket"`,
-- the command IDs and the packet read into globals, statements ended by
-- semicolons, pcall around each packet's work and "Error occured" when it
-- fails, printf with %d. It is the project's own text, following the
-- shape SCRIPTING.md describes.
--
-- B0h: the state (19 bytes: E_SUCCESS, the low byte of the flags,
--      position, speed, force and socket.gettime() as float32 LE).
-- B1h (8 bytes: width, speed as float32 LE): stop if busy, then a
--      prepositioning (mc.move), then the state.
-- B2h: the state and the two finger forces, NaN without force fingers,
--      as one old published script wrote it: with math.nan, which a real
--      gripper does not have, so the packet fails and gets no answer.

require "socket"

cmd.unregister(0xB0);
cmd.register(0xB0);
cmd.register(0xB1);
cmd.register(0xB2);

nfin = 0;
for i = 0, 1 do
    if finger.type(i) == "fmf" then
        nfin = nfin + 1;
    else
        break;
    end
end
printf("#FMF fingers: %d\n", nfin)

function hasbit(x, p)
    return x % (p + p) >= p
end

function send_state(extra)
    state = gripper.state();
    pos = mc.position();
    speed = mc.speed();
    force = mc.aforce();
    time = socket.gettime();
    if cmd.online() then
        if extra then
            cmd.send(id, etob(E_SUCCESS), state % 256, ntob(pos), ntob(speed),
                     ntob(force), ntob(time), extra);
        else
            cmd.send(id, etob(E_SUCCESS), state % 256, ntob(pos), ntob(speed),
                     ntob(force), ntob(time));
        end
    end
end

function process()
    id, payload = cmd.read();
    if id == 0xB1 then
        width = bton({payload[1], payload[2], payload[3], payload[4]});
        v = bton({payload[5], payload[6], payload[7], payload[8]});
        if mc.busy() then
            mc.stop();
        end
        mc.move(width, v, 0);
    end
    if id == 0xB2 then
        if nfin == 2 then
            send_state({ntob(finger.data(0)), ntob(finger.data(1))});
        else
            send_state({ntob(math.nan), ntob(math.nan)});
        end
        return;
    end
    send_state();
end

while true do
    if cmd.online() then
        if not pcall(process) then
            print("Error occured");
            sleep(100);
        end
    else
        sleep(100);
    end
end
