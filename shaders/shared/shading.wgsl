//! use shared/common.wgsl
// The LEDs' light on the painted skin and the pixel it makes, applied by the camera stage's
// passes where each ray lands (the reference frame's and a contact's touched pixels): no
// G-buffer round trip, whose loads and stores llvmpipe makes lane by lane. Mirror:
// src/render/leds.rs.

// x^e for x >= 0. A whole exponent up to 255 (the paper sensor's are 2 and 24) is multiplied
// out by squaring: the exponents are pipeline constants (LED_SPREAD, PAINT_SHININESS), so the
// driver unrolls the loop, folds the bit tests and keeps only the multiplies, where pow is
// exp2(e log2 x), two polynomials on llvmpipe. Other exponents take pow.
fn power(x: f32, e: f32) -> f32 {
    if e != floor(e) || e < 0.0 || e > 255.0 {
        return pow(x, e);
    }
    var n = u32(e);
    var result = 1.0;
    var square = x;
    for (var k = 0u; k < 8u; k++) {
        if (n & 1u) != 0u {
            result *= square;
        }
        square *= square;
        n = n >> 1u;
    }
    return result;
}

// Relative emission of LED i towards unit direction `towards`: the LEDs shine up the finger
// (+z). Their shared spread is a pipeline constant; -1 means each has its own.
fn emission(i: i32, towards: vec3<f32>) -> f32 {
    var spread = LED_SPREAD;
    if spread < 0.0 {
        spread = sensor.led_light[i].y;
    }
    return power(max(towards.z, 0.0), spread);
}

fn shade(p: vec3<f32>, normal: vec3<f32>, ray: vec3<f32>, moved: bool) -> vec3<f32> {
    // The paint faces the inside of the finger, where the camera and the LEDs are.
    let facing = -normal;
    let view = -ray;
    var colour = sensor.ambient.xyz;
    var place: GelPlace;
    if GEL_LEDS || AMBIENT_RELIEF {
        place = gel_place(p, normal);
    }
    // Only moved skin is tilted: the empty finger keeps the flat ambient's exact light.
    if AMBIENT_RELIEF && moved {
        colour = ambient_light(place);
    }
    for (var i = 0; i < LED_COUNT; i++) {
        if GEL_LEDS && sensor.led_position[i].w == 1.0 {
            colour += sensor.led_colour[i].xyz * (sensor.led_light[i].x * gel_light(i, place));
            continue;
        }
        let to_led = sensor.led_position[i].xyz - p;
        let dist = length(to_led);
        let l = to_led / dist;
        let lambert = dot(facing, l);
        if lambert <= 0.0 {
            continue;
        }
        let d = dist / sensor.led_light[i].z;
        let falloff = emission(i, -l) / (1.0 + d * d);
        let half_vector = normalize(l + view);
        let spec = power(max(dot(facing, half_vector), 0.0), PAINT_SHININESS);
        colour += sensor.led_colour[i].xyz * (sensor.led_light[i].x * falloff * (sensor.diffuse * lambert + sensor.specular * spec));
    }
    if SHELL_END {
        colour = shell_end_light(colour, ray);
    }
    return colour * sensor.paint_colour.xyz;
}

// The ambient light at `place`: each channel times the skin's tilt against the way up the
// finger, as a gel LED's glow. Mirror: src/render/leds.rs ambient_light.
fn ambient_light(place: GelPlace) -> vec3<f32> {
    return sensor.ambient.xyz * max(vec3<f32>(1.0) + sensor.ambient_relief.xyz * place.tilt_up, vec3<f32>(0.0));
}

// The light `colour` of the skin a camera ray sees, past a clear shell's open end: through
// the shell it brightens towards the end's edge (in each LED's tint round it when
// END_GLOW); through the open end it is the tip's own light plus the share of the LEDs'
// that reaches it. Mirror: src/render/leds.rs shell_end_light.
fn shell_end_light(colour: vec3<f32>, ray: vec3<f32>) -> vec3<f32> {
    if ray.z <= 0.0 {
        return colour;
    }
    let end = sensor.shell_end;
    let outside = end.x * length(ray.xy) / ray.z - end.y;
    let beyond = 1.0 / (1.0 + exp(clamp(outside / SHELL_EDGE_MM, -40.0, 40.0)));
    let fade = exp(-max(outside, 0.0) / end.w);
    var rim = vec3<f32>(1.0 + end.z * fade);
    if END_GLOW {
        rim = max(vec3<f32>(1.0) + (vec3<f32>(end.z) + end_glow(ray)) * fade, vec3<f32>(0.0));
    }
    let scale = beyond * sensor.shell_tip.w + (1.0 - beyond) * rim;
    return colour * scale + sensor.shell_tip.xyz * beyond;
}

// The LEDs' own glow at the shell's end where `ray` crosses it, per channel: each LED's
// end_glow weighted by a von Mises bump in azimuth about it, exp((cos turn - 1) / s^2).
// Mirror: src/render/leds.rs end_glow.
fn end_glow(ray: vec3<f32>) -> vec3<f32> {
    let len = length(ray.xy);
    if len <= 0.0 {
        return vec3<f32>(0.0);
    }
    let towards = ray.xy / len;
    var glow = vec3<f32>(0.0);
    for (var i = 0; i < LED_COUNT; i++) {
        let led = sensor.led_position[i].xy;
        let led_len = length(led);
        var cos_turn = 0.0;
        if led_len > 0.0 {
            cos_turn = dot(towards, led / led_len);
        }
        glow += sensor.led_end_glow[i].xyz * exp((cos_turn - 1.0) * sensor.shell_glow.x);
    }
    return glow;
}

// Where a skin point lies for the gel's light, found once per pixel for every gel LED and the
// ambient: its azimuth, latitude above the hemisphere's equator, height up the skin (z on
// the cylinder, the hemisphere's centre's z plus the arc above the equator) and how far its
// normal tilts up the finger. Mirror: src/render/leds.rs GelPlace.
struct GelPlace {
    azimuth: f32,
    cos_latitude: f32,
    height: f32,
    tilt_up: f32,
}

fn gel_place(p: vec3<f32>, normal: vec3<f32>) -> GelPlace {
    let r = sensor.radius;
    let d = sensor.cylinder_length;
    let azimuth = atan2(p.y, p.x);
    var latitude = 0.0;
    var height = p.z;
    if p.z > d {
        latitude = atan2(p.z - d, length(p.xy));
        height = d + r * latitude;
    }
    let way_up = vec3<f32>(-sin(latitude) * cos(azimuth), -sin(latitude) * sin(azimuth), cos(latitude));
    return GelPlace(azimuth, cos(latitude), height, dot(normal, way_up));
}

// How bright gel LED i makes the skin at `place`: a band up the finger above the LED that
// widens and fades, times the skin's tilt against the light's path. Mirror:
// src/render/leds.rs gel_light.
fn gel_light(i: i32, place: GelPlace) -> f32 {
    let led = sensor.led_position[i].xyz;
    let band = sensor.led_band[i];
    let up = max(place.height - led.z, 0.0);
    var turn = place.azimuth - atan2(led.y, led.x);
    turn -= TAU * round(turn / TAU);
    let across = sensor.radius * turn * place.cos_latitude;
    let width = band.x + band.y * up;
    let g = across / width;
    let glow = exp(-0.5 * g * g - up / band.z) * (band.x / width);
    return glow * max(1.0 + band.w * place.tilt_up, 0.0);
}

// One 8-bit value from a linear channel and one over the camera's gamma for it.
fn encode_gamma(linear: f32, inverse_gamma: f32) -> u32 {
    let v = pow(clamp(linear, 0.0, 1.0), inverse_gamma) * 255.0;
    return u32(clamp(round(v), 0.0, 255.0));
}

fn encode(linear: f32) -> u32 {
    let v = pow(clamp(linear, 0.0, 1.0), 1.0 / 2.2) * 255.0;
    return u32(clamp(round(v), 0.0, 255.0));
}

fn pack_rgba(c: vec3<u32>) -> u32 {
    return c.x | (c.y << 8u) | (c.z << 16u) | (255u << 24u);
}

// Pixel i's colour from the linear light `colour` (black beyond the lens), vignetted, and the
// indentation it sees. Mirror: src/render/leds.rs pixel_colour.
fn write_pixel(xy: vec2<u32>, colour: vec3<f32>, depth: f32) {
    let i = image_index(xy);
    var c = colour;
    if VIGNETTING {
        let r = length(vec2<f32>(xy) - sensor.principal) * sensor.vignetting.z;
        let r2 = r * r;
        c = c * (1.0 + sensor.vignetting.x * r2 + sensor.vignetting.y * r2 * r2);
    }
    if CAMERA_RESPONSE {
        let m = vec3<f32>(dot(sensor.colour_matrix[0].xyz, c), dot(sensor.colour_matrix[1].xyz, c), dot(sensor.colour_matrix[2].xyz, c));
        let g = sensor.inverse_gamma;
        image[i] = pack_rgba(vec3<u32>(encode_gamma(m.x, g.x), encode_gamma(m.y, g.y), encode_gamma(m.z, g.z)));
    } else {
        image[i] = pack_rgba(vec3<u32>(encode(c.x), encode(c.y), encode(c.z)));
    }
    indentation[i] = depth;
}
