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

// Relative emission towards unit direction `towards`: the LEDs shine up the finger (+z).
fn emission(towards: vec3<f32>) -> f32 {
    return power(max(towards.z, 0.0), LED_SPREAD);
}

fn shade(p: vec3<f32>, normal: vec3<f32>, ray: vec3<f32>) -> vec3<f32> {
    // The paint faces the inside of the finger, where the camera and the LEDs are.
    let facing = -normal;
    let view = -ray;
    var colour = vec3<f32>(sensor.ambient);
    for (var i = 0; i < 3; i++) {
        let to_led = sensor.led_position[i].xyz - p;
        let dist = length(to_led);
        let l = to_led / dist;
        let lambert = dot(facing, l);
        if lambert <= 0.0 {
            continue;
        }
        let d = dist / sensor.falloff_mm;
        let falloff = emission(-l) / (1.0 + d * d);
        let half_vector = normalize(l + view);
        let spec = power(max(dot(facing, half_vector), 0.0), PAINT_SHININESS);
        colour += sensor.led_colour[i].xyz * (sensor.intensity * falloff * (sensor.diffuse * lambert + sensor.specular * spec));
    }
    return colour;
}

fn encode(linear: f32) -> u32 {
    let v = pow(clamp(linear, 0.0, 1.0), 1.0 / 2.2) * 255.0;
    return u32(clamp(round(v), 0.0, 255.0));
}

fn pack_rgba(c: vec3<u32>) -> u32 {
    return c.x | (c.y << 8u) | (c.z << 16u) | (255u << 24u);
}

// Pixel i's colour from the linear light `colour` (black beyond the lens) and the
// indentation it sees.
fn write_pixel(xy: vec2<u32>, colour: vec3<f32>, depth: f32) {
    let i = image_index(xy);
    image[i] = pack_rgba(vec3<u32>(encode(colour.x), encode(colour.y), encode(colour.z)));
    indentation[i] = depth;
}

// Where pixel xy lies in the image and indentation buffers, which hold only the rect of the
// image a frame can change (a contact frame copies, clears and reads back that much).
fn image_index(xy: vec2<u32>) -> u32 {
    return (xy.y - frame.image_y) * frame.image_pitch + (xy.x - frame.image_x);
}
