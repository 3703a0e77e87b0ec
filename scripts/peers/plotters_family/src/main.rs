//! The tuning-curve family of `host-sim curve --json` drawn with plotters (SVG backend): the
//! same data, palette and labels as host-sim's docs/plots/curve-family.svg (a colour per λ2p,
//! each group's safe-region edge dashed, its two ends labelled with their λ1p), each label
//! where plotters puts it, beside its point: plotters places no label for you.
//! Usage: plotters_family CURVE.json OUT.svg
use plotters::prelude::*;
use serde_json::Value;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, input, out] = &args[..] else {
        return Err("usage: plotters_family CURVE.json OUT.svg".into());
    };
    let json: Value = serde_json::from_str(&std::fs::read_to_string(input)?)?;
    let curves = json["curves"].as_array().ok_or("no curves")?;
    let f = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    let root = SVGBackend::new(out, (760, 400)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("Tuning curve: reference device", ("sans-serif", 14))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..14500f64, 41.5f64..49f64)?;
    chart
        .configure_mesh()
        .x_desc("bias, V")
        .y_desc("natural frequency, Hz")
        .draw()?;
    let colours = [
        RGBColor(0, 0x72, 0xB2),
        RGBColor(0xE6, 0x9F, 0),
        RGBColor(0, 0x9E, 0x73),
    ];
    let mut groups: Vec<f64> = Vec::new();
    for c in curves {
        if !groups.contains(&f(&c["prestretch_2"])) {
            groups.push(f(&c["prestretch_2"]));
        }
    }
    for (g, &l2) in groups.iter().enumerate() {
        let colour = colours[g % colours.len()];
        let members: Vec<&Value> = curves
            .iter()
            .filter(|c| f(&c["prestretch_2"]) == l2)
            .collect();
        for (k, c) in members.iter().enumerate() {
            let points = c["points"].as_array().ok_or("no points")?;
            let line = points
                .iter()
                .map(|p| (f(&p["bias_volts"]), f(&p["natural_frequency_hz"])));
            let series = chart.draw_series(LineSeries::new(line, colour.stroke_width(1)))?;
            if k == 0 {
                series
                    .label(format!("λ2p {l2}"))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour));
            }
        }
        let edge: Vec<(f64, f64, f64)> = members
            .iter()
            .filter(|c| c["limit"].is_object())
            .map(|c| {
                let l = &c["limit"];
                (f(&l["volts"]), f(&l["natural_frequency_hz"]), f(&c["prestretch_1"]))
            })
            .collect();
        chart.draw_series(DashedLineSeries::new(
            edge.iter().map(|e| (e.0, e.1)),
            5,
            3,
            colour.stroke_width(1),
        ))?;
        for end in [edge.first(), edge.last()].into_iter().flatten() {
            chart.draw_series(std::iter::once(Text::new(
                format!("λ1p {}", end.2),
                (end.0, end.1),
                ("sans-serif", 11).into_font().color(&colour),
            )))?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
