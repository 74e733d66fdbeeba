-- tip_reader.lua: a script on the gripper that reads the two example
-- finger devices as public scripts read theirs: finger 0's tactile tip
-- over UART (power-cycled first, "z" answered "x", then "a" and 50 bytes),
-- finger 1's SPI sensor polled until its first byte is 42. B0h answers
-- E_SUCCESS, 1 if the tip said "x", the tip's 50 bytes and the sensor's 3.
-- Run: wsgemu --finger0 device:tactile_tip.lua \
--             --finger1 device:spi_sensor.lua --script tip_reader.lua
cmd.register(0xB0)
finger.power(0, false)
sleep(300)
finger.power(0, true)
finger.interface(0, "uart", 115200)
sleep(100)
finger.write(0, "z")
sleep(100)
local alive = 0
if finger.bytes_available(0) > 0 and finger.read(0, 1)[1] == 120 then
  alive = 1
end
finger.interface(1, "spi", 1000000, 8, 0)
local r = finger.spi(1, {0, 0, 0})
while r[1] ~= 42 do
  sleep(10)
  r = finger.spi(1, {0, 0, 0})
end
while true do
  local id = cmd.read()
  finger.write(0, "a")
  while finger.bytes_available(0) < 50 do sleep(1) end
  cmd.send(id, etob(E_SUCCESS), alive, finger.read(0, 50),
           finger.spi(1, {0, 0, 0}))
end
