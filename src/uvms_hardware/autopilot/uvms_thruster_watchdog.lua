-- uvms_thruster_watchdog.lua: the thrusters stop on the autopilot's side when the UVMS bridge stops.
--
-- Runs on ArduSub (Lua scripting, SCR_ENABLE = 1; install steps in docs/hardware.md, section
-- "The autopilot watchdog script"). The ardusub_bridge sends each thruster's PWM on RC input
-- FIRST_RC + n - 1 for thruster output n (RC_CHANNELS_OVERRIDE channels 9-16, which ArduSub
-- does not take as pilot inputs), every value of one message with the same parity (even, then
-- odd in the next message: the lowest bit is a toggle, 2 us of resolution). Every PERIOD_MS:
--
-- * armed, and the toggle flipped within TIMEOUT_MS (our bridge is alive and commanding):
--   each thruster output gets its PWM (toggle bit cleared, clamped to MIN_US..MAX_US) with
--   SRV_Channels:set_output_pwm_chan_timeout(output - 1, pwm, TIMEOUT_MS);
-- * armed, after driving, and no flip for TIMEOUT_MS (the bridge died, hung or lost the link):
--   NEUTRAL_US on every thruster output, with the same timeout, until the vehicle is disarmed;
-- * disarmed: nothing; the outputs are their Motor1..8 function again, neutral while disarmed.
--
-- If this script stops (an error, SCR_ENABLE 0), each override expires after TIMEOUT_MS and
-- the outputs return to their Motor function: no SERVOn_FUNCTION is changed, nothing is saved.
-- A pilot's ground station cannot look like the bridge: ArduSub's own joystick handling writes
-- channels 9-11 (lights, video switch) with constant values, which never toggle.
-- Once a second: NAMED_VALUE_FLOAT 'UVMS_WD' = TIMEOUT_MS, which the bridge listens for at
-- configure. Facts (ArduPilot sources): set_output_pwm_chan_timeout takes a 0-based output and
-- forces the value over the output's function until the timeout (SRV_Channels.cpp,
-- SRV_Channel.cpp); rc:get_pwm(n) is RC channel n's input, which keeps the last override when
-- no receiver is fitted (RC_Channel.cpp); AP_Motors6DOF outputs neutral while disarmed.

local TIMEOUT_MS = 100
local PERIOD_MS = 10
local FIRST_RC = 9
local OUTPUTS = {1, 2, 3, 4, 5, 6, 7, 8}
local NEUTRAL_US = 1500
local MIN_US = 1100
local MAX_US = 1900
local ANNOUNCE_MS = 1000

local last_parity = -1
local flipped = false
local last_flip_ms = millis()
local driving = false
local last_announce_ms = millis()

-- Each thruster's PWM with the toggle bit cleared and the toggle, or nil when the inputs are
-- not one message of the bridge (missing, out of range, or of mixed parity).
local function read_inputs()
  local values = {}
  local parity = nil
  for i = 1, #OUTPUTS do
    local pwm = rc:get_pwm(FIRST_RC + OUTPUTS[i] - 1)
    if pwm == nil or pwm < 1000 or pwm > 2000 then
      return nil, nil
    end
    local bit = pwm % 2
    if parity == nil then
      parity = bit
    elseif parity ~= bit then
      return nil, nil
    end
    values[i] = pwm - bit
  end
  return values, parity
end

local function set_all(values)
  for i = 1, #OUTPUTS do
    local pwm = NEUTRAL_US
    if values ~= nil then
      pwm = math.max(MIN_US, math.min(MAX_US, values[i]))
    end
    SRV_Channels:set_output_pwm_chan_timeout(OUTPUTS[i] - 1, pwm, TIMEOUT_MS)
  end
end

function update()
  local now = millis()
  local values, parity = read_inputs()
  if parity ~= nil and parity ~= last_parity then
    if last_parity ~= -1 then
      flipped = true
      last_flip_ms = now
    end
    last_parity = parity
  end
  local fresh = flipped and (now - last_flip_ms) <= TIMEOUT_MS
  if arming:is_armed() then
    if fresh and values ~= nil then
      driving = true
      set_all(values)
    elseif driving then
      set_all(nil)
    end
  else
    driving = false
  end
  if (now - last_announce_ms) >= ANNOUNCE_MS then
    last_announce_ms = now
    gcs:send_named_float('UVMS_WD', TIMEOUT_MS)
  end
  return update, PERIOD_MS
end

gcs:send_text(6, 'uvms_thruster_watchdog: running')
return update, PERIOD_MS
