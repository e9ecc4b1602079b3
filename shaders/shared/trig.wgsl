// f32 trigonometry written out (textbook forms with the project's own near-minimax
// coefficients, scripts/fit_polynomials.py; ~1-3 ulp): Vulkan only promises sin/cos to
// 2^-11 absolute and atan2 to 4096 ulp. Twin: src/model/real.rs `ktrig`.

const PIO2_HI: f32 = 1.5707963;
const PIO2_LO: f32 = -4.371139e-8;

fn ksin_cos(x: f32) -> vec2<f32> {
    let k = round(x * 0.63661975);
    let r = (x - k * PIO2_HI) - k * PIO2_LO;
    let z = r * r;
    let s = r + r * z * (-1.6666655e-1 + z * (8.332178e-3 + z * -1.9517238e-4));
    let c = 1.0 - 0.5 * z + z * z * (4.1666646e-2 + z * (-1.3887367e-3 + z * 2.4438375e-5));
    let q = ((i32(k) % 4) + 4) % 4;
    if (q == 0) { return vec2<f32>(s, c); }
    if (q == 1) { return vec2<f32>(c, -s); }
    if (q == 2) { return vec2<f32>(-s, -c); }
    return vec2<f32>(-c, s);
}

fn katan_unit(t: f32) -> f32 {
    var u = t;
    var off = 0.0;
    if (t > 0.41421357) {
        u = (t - 1.0) / (t + 1.0);
        off = 0.78539816;
    }
    let z = u * u;
    return off + ((((8.0598384e-2 * z - 1.3879716e-1) * z + 1.9977915e-1) * z - 3.3332956e-1) * z * u + u);
}

fn katan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    if (ax == 0.0 && ay == 0.0) { return 0.0; }
    var a: f32;
    if (ay <= ax) { a = katan_unit(ay / ax); } else { a = 1.5707964 - katan_unit(ax / ay); }
    if (x < 0.0) { a = 3.1415927 - a; }
    if (y < 0.0) { return -a; }
    return a;
}
